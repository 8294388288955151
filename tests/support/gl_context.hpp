#pragma once
// What the GLSL tests share: one headless EGL context on Mesa's llvmpipe (docs/design.md#glsl-on-the-cpu),
// shader compilation and linking with their logs as errors, buffers, and glslangValidator runs.
// Included by the GPU test executables only (they link EGL and OpenGL).

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

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

// One context per process, made once and never terminated (eglTerminate under ASan reports the
// driver's unloading as a leak). A context that cannot be made throws: the test fails, never skips.
// An EGL error code as the headers spell it (0x3001 EGL_NOT_INITIALIZED ...): hexadecimal.
inline std::string egl_error_text(EGLint code)
{
    char text[16];
    std::snprintf(text, sizeof text, "0x%04X", unsigned(code));
    return text;
}

inline void require_context()
{
    static bool ready = false;
    if (ready) return;
    const EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY) throw std::runtime_error("eglGetPlatformDisplay(surfaceless) failed");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor))
        throw std::runtime_error("eglInitialize failed: " + egl_error_text(eglGetError()) +
                                 " (is libgl1-mesa-dri installed? configure with -DKRS_GLSL_TESTS=OFF to skip)");
    if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error("eglBindAPI(EGL_OPENGL_API) failed");
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    const EGLContext context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) throw std::runtime_error("eglCreateContext(4.3 core) failed");
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) throw std::runtime_error("eglMakeCurrent failed");
    ready = true;
}

inline GLuint compile(GLenum stage, const std::string& text)
{
    const GLuint shader = glCreateShader(stage);
    const char* source = text.c_str();
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetShaderInfoLog(shader, sizeof log, nullptr, log);
        glDeleteShader(shader);
        throw std::runtime_error(std::string("shader compilation failed: ") + log);
    }
    return shader;
}

inline GLuint link(std::initializer_list<GLuint> shaders)
{
    const GLuint program = glCreateProgram();
    for (GLuint s : shaders) glAttachShader(program, s);
    glLinkProgram(program);
    for (GLuint s : shaders) glDeleteShader(s);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetProgramInfoLog(program, sizeof log, nullptr, log);
        glDeleteProgram(program);
        throw std::runtime_error(std::string("program link failed: ") + log);
    }
    return program;
}

inline GLuint buffer(GLenum target, const void* data, std::size_t bytes, GLenum usage)
{
    GLuint b = 0;
    glGenBuffers(1, &b);
    glBindBuffer(target, b);
    glBufferData(target, GLsizeiptr(bytes), data, usage);
    return b;
}

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
