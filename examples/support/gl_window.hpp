#pragma once
// A window with an OpenGL 3.3 core context, made by GLFW (Debian's libglfw3-dev), for the examples
// that draw on screen (krs_view). Opening it fails with GLFW's own reason ("X11: The DISPLAY
// environment variable is missing", "GLX: Failed to create context: ..."), as a window_error the
// caller prints: no display and no 3.3 context are the user's situation, not a crash.
//
// The GL functions are called through GLVND's libOpenGL (CMake's OpenGL::OpenGL), as the GLSL tests
// do (tests/support/gl_program.hpp): on Linux every entry point it exports dispatches to the
// context current on the calling thread, whichever window system made it (GLX here, EGL in the
// tests), so neither a loader library (glad, libepoxy) nor a table of glfwGetProcAddress pointers
// is needed. A platform whose GL library exports only OpenGL 1.1 (Windows' opengl32) would need a
// loader; the examples build on Debian.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE // GLFW must not include another GL header after glcorearb.h
#include <GLFW/glfw3.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace example {

// A window or context that could not be made, with GLFW's reason.
class window_error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

namespace detail {
// GLFW reports errors through a callback; the last description is what a failed call returns.
inline std::string& last_glfw_error()
{
    static std::string text;
    return text;
}
inline void remember_glfw_error(int, const char* description)
{
    last_glfw_error() = description ? description : "unknown GLFW error";
}
} // namespace detail

class gl_window {
public:
    // A width x height window (screen coordinates) titled `title`, with its 3.3 core context
    // current. `visible` false keeps it off screen: the headless runs draw into their own
    // framebuffers, so what the window would show does not matter (and a hidden window works on
    // a virtual display without a window manager).
    gl_window(const std::string& title, int width, int height, bool visible)
    {
        glfwSetErrorCallback(detail::remember_glfw_error);
        if (!glfwInit()) throw window_error(detail::last_glfw_error());
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE); // macOS gives 3.3 core only so
        glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
        window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window_) {
            const std::string why = detail::last_glfw_error();
            glfwTerminate();
            throw window_error(why);
        }
        glfwMakeContextCurrent(window_);
    }
    gl_window(const gl_window&) = delete;
    gl_window& operator=(const gl_window&) = delete;
    ~gl_window()
    {
        glfwDestroyWindow(window_);
        glfwTerminate();
    }

    GLFWwindow* handle() const { return window_; }
    bool should_close() const { return glfwWindowShouldClose(window_) != 0; }
    void set_title(const std::string& title) { glfwSetWindowTitle(window_, title.c_str()); }
    // The drawable size in pixels (larger than the window's size on a high-density screen).
    std::pair<int, int> framebuffer_size() const
    {
        int w = 0, h = 0;
        glfwGetFramebufferSize(window_, &w, &h);
        return {w, h};
    }
    // The pointer in pixels from the drawable's bottom-left corner (GL's and iMouse's y up).
    std::pair<float, float> pointer() const
    {
        double x = 0, y = 0;
        glfwGetCursorPos(window_, &x, &y);
        int ww = 1, wh = 1;
        glfwGetWindowSize(window_, &ww, &wh);
        const auto [fw, fh] = framebuffer_size();
        const double sx = double(fw) / double(ww > 0 ? ww : 1),
                     sy = double(fh) / double(wh > 0 ? wh : 1);
        return {float(x * sx), float(double(fh) - y * sy)};
    }

private:
    GLFWwindow* window_ = nullptr;
};

} // namespace example
