#pragma once
// A GL program built from a vertex and a fragment shader's text, or the compiler's log: a viewer
// that reloads a user's file must go on with its last good program when the new one fails, so a
// failure is a value (the log), not an exception. The program is deleted with its owner.

//
// Also what the GLSL tests compile their shaders with (tests/support/gl_program.hpp): one rule for
// a shader and its log. Only GL's header is needed here (the functions come from GLVND's
// libOpenGL, examples/support/gl_window.hpp says why), so the tests include it without GLFW.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <string>
#include <utility>

namespace example {

// The info log of a shader (get = glGetShaderiv, read = glGetShaderInfoLog) or a program (their
// Program twins), read whole, however long the driver's message is.
template <class Get, class Read>
std::string gl_info_log(GLuint object, Get get, Read read)
{
    GLint length = 0;
    get(object, GL_INFO_LOG_LENGTH, &length);
    std::string text(std::size_t(length > 1 ? length : 1), '\0');
    read(object, GLsizei(text.size()), nullptr, text.data());
    text.resize(text.find('\0') == std::string::npos ? text.size() : text.find('\0'));
    return text;
}

// A compiled shader of `stage`, or 0 with the compiler's log in `log`.
inline GLuint compile_shader(GLenum stage, const std::string& text, std::string& log)
{
    const GLuint shader = glCreateShader(stage);
    const char* source = text.c_str();
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint compiled = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &compiled);
    if (compiled) return shader;
    log = gl_info_log(shader, glGetShaderiv, glGetShaderInfoLog);
    glDeleteShader(shader);
    return 0;
}

// The full-screen triangle from gl_VertexID alone (a core context still needs a vertex array
// bound).
inline const char* const fullscreen_triangle_vertex_shader = R"(#version 330 core
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

class gl_program {
public:
    gl_program() = default;
    gl_program(const gl_program&) = delete;
    gl_program& operator=(const gl_program&) = delete;
    gl_program(gl_program&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    gl_program& operator=(gl_program&& other) noexcept
    {
        std::swap(id_, other.id_);
        return *this;
    }
    ~gl_program()
    {
        if (id_ != 0) glDeleteProgram(id_);
    }

    // Compiles and links; on failure returns an empty program and puts the log (which stage, then
    // the driver's own text) in `log`.
    static gl_program build(const std::string& vertex, const std::string& fragment,
                            std::string& log)
    {
        log.clear();
        std::string why;
        const GLuint v = compile_shader(GL_VERTEX_SHADER, vertex, why);
        if (v == 0) log = "vertex shader: " + why;
        const GLuint f = v == 0 ? 0 : compile_shader(GL_FRAGMENT_SHADER, fragment, why);
        if (v != 0 && f == 0) log = "fragment shader: " + why;
        gl_program p;
        if (v == 0 || f == 0) {
            if (v != 0) glDeleteShader(v);
            return p;
        }
        p.id_ = glCreateProgram();
        glAttachShader(p.id_, v);
        glAttachShader(p.id_, f);
        glLinkProgram(p.id_);
        glDeleteShader(v); // flagged: freed with the program
        glDeleteShader(f);
        GLint linked = 0;
        glGetProgramiv(p.id_, GL_LINK_STATUS, &linked);
        if (!linked) {
            log = "link: " + gl_info_log(p.id_, glGetProgramiv, glGetProgramInfoLog);
            return gl_program();
        }
        return p;
    }

    explicit operator bool() const { return id_ != 0; }
    GLuint id() const { return id_; }
    GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }

private:
    GLuint id_ = 0;
};

} // namespace example
