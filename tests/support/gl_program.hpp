#pragma once
// One headless EGL context on Mesa's llvmpipe (docs/design.md#glsl-on-the-cpu), shader compilation
// and linking with their logs as errors, and buffers: what the GLSL tests and
// bench/bench_glsl_llvmpipe.cpp share. No doctest here, so the bench can include it.

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include "../../examples/support/gl_shader.hpp" // example::compile_shader: the examples' rule, shared

#include <cstdio>
#include <initializer_list>
#include <stdexcept>
#include <string>

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

// A shader that does not compile throws with the compiler's log (the test fails).
inline GLuint compile(GLenum stage, const std::string& text)
{
    std::string log;
    const GLuint shader = example::compile_shader(stage, text, log);
    if (shader == 0) throw std::runtime_error("shader compilation failed: " + log);
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
        const std::string log = example::gl_info_log(program, glGetProgramiv, glGetProgramInfoLog);
        glDeleteProgram(program);
        throw std::runtime_error("program link failed: " + log);
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

} // namespace krs_test
