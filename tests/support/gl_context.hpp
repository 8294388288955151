#pragma once
// What the GLSL tests share: the context, shaders and buffers of gl_program.hpp, a full-screen draw,
// and glslangValidator and spirv-val runs.
// Included by the GPU test executables only (they link EGL and OpenGL).

#include "gl_program.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace krs_test {

// A vertex shader that covers the viewport with one triangle, from gl_VertexID alone.
inline const std::string fullscreen_vertex_shader = "#version 430 core\n"
                                                    "void main() {\n"
                                                    "    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
                                                    "    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
                                                    "}\n";

// Runs `program` (built with fullscreen_vertex_shader) once per pixel of a width x height RGBA32F
// framebuffer; set_uniforms() runs after glUseProgram. Returns RGBA floats, rows bottom-up as
// glReadPixels gives them. The program stays the caller's.
template <class SetUniforms>
std::vector<float> draw_fullscreen(GLuint program, int width, int height, SetUniforms&& set_uniforms)
{
    GLuint framebuffer = 0, color = 0, vao = 0;
    glGenFramebuffers(1, &framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glGenRenderbuffers(1, &color);
    glBindRenderbuffer(GL_RENDERBUFFER, color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    REQUIRE(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    glViewport(0, 0, width, height);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glUseProgram(program);
    set_uniforms();
    glDrawArrays(GL_TRIANGLES, 0, 3);
    std::vector<float> pixels(std::size_t(width) * std::size_t(height) * 4);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    glDeleteVertexArrays(1, &vao);
    glDeleteRenderbuffers(1, &color);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &framebuffer);
    return pixels;
}

// glslangValidator (the path CMake found) on one file, its stage from the extension; fails the
// test with the validator's message.
inline void validate_with_glslang(const std::string& path, const std::string& text)
{
    {
        std::ofstream out(path, std::ios::binary);
        out << text;
        REQUIRE(out.good());
    }
    const std::string log = path + ".log";
    const int status = std::system(("\"" KRS_GLSLANG_VALIDATOR "\" -l \"" + path + "\" > \"" + log + "\" 2>&1").c_str());
    std::ifstream in(log);
    const std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    INFO(path << ":\n" << message);
    CHECK(status == 0);
}

// The same text for Vulkan: glslangValidator -V compiles it to SPIR-V for Vulkan 1.0 and spirv-val
// (the paths CMake found) validates the module; either's complaint fails the test.
inline void validate_spirv(const std::string& path, const std::string& text)
{
    {
        std::ofstream out(path, std::ios::binary);
        out << text;
        REQUIRE(out.good());
    }
    const std::string log = path + ".spv.log";
    const std::string compile = "\"" KRS_GLSLANG_VALIDATOR "\" -V --target-env vulkan1.0 -o \"" + path + ".spv\" \"" +
                                path + "\" > \"" + log + "\" 2>&1";
    const std::string validate = "\"" KRS_SPIRV_VAL "\" --target-env vulkan1.0 \"" + path + ".spv\" >> \"" + log + "\" 2>&1";
    const int status = std::system((compile + " && " + validate).c_str());
    std::ifstream in(log);
    const std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    INFO(path << " (Vulkan):\n" << message);
    CHECK(status == 0);
}

} // namespace krs_test
