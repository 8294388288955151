#pragma once
// A Shadertoy program (its Image tab: a `mainImage(out vec4, in vec2)` and the functions it calls)
// run as Shadertoy runs it, in an OpenGL 3.3 core context: the inputs Shadertoy gives (iResolution,
// iTime, iTimeDelta, iFrame, iMouse) declared as uniforms around the user's text, and one
// full-screen triangle so mainImage runs once per pixel with fragCoord at the pixel's center.
//
// Progressive anti-aliasing needs the same pixel seen through other points of its square, and a
// Shadertoy mainImage takes no jitter: the host moves fragCoord instead (krs_jitter, in pixels,
// 0 for the plain frame), so every program, the emitted ones and a user's, is anti-aliased the
// same way and a frame without jitter is the program's own.
//
// The user's text starts at line 1 (`#line 1`): the compiler's log then names the file's own lines
// ("0:12(5): error: ..." on Mesa), not the host's.

#include "gl_shader.hpp"
#include "gl_window.hpp"

#include <array>
#include <string>

namespace example {

// What Shadertoy passes a frame. iMouse follows Shadertoy: xy is the pointer while a button is
// held (pixels from the bottom-left corner) and stays where it was released; zw is where the
// button went down, negated once it is up; all 0 until the first click.
struct shadertoy_inputs {
    float width = 1, height = 1; // iResolution.xy, pixels
    float time = 0;              // iTime, seconds
    float time_delta = 0;        // iTimeDelta
    int frame = 0;               // iFrame, frames since the program was (re)loaded
    std::array<float, 4> mouse{};
    std::array<float, 2> jitter{}; // fragCoord's offset from the pixel center, in pixels
};

// iMouse from the button and the pointer, frame by frame (see shadertoy_inputs::mouse).
class shadertoy_mouse {
public:
    void update(bool pressed, float x, float y)
    {
        if (pressed) {
            if (!down_) value_[2] = x, value_[3] = y; // the click
            value_[0] = x, value_[1] = y;
        } else if (down_) {
            value_[2] = -value_[2], value_[3] = -value_[3];
        }
        down_ = pressed;
    }
    bool dragging() const { return down_; }
    const std::array<float, 4>& value() const { return value_; }

private:
    std::array<float, 4> value_{};
    bool down_ = false;
};

// The fragment shader that runs `image` (a Shadertoy Image tab's text) as described above.
inline std::string shadertoy_fragment_shader(const std::string& image)
{
    std::string out = "#version 330 core\n"
                      "uniform vec3 iResolution;\nuniform float iTime;\nuniform float iTimeDelta;\n"
                      "uniform int iFrame;\nuniform vec4 iMouse;\nuniform vec2 krs_jitter;\n"
                      "out vec4 krs_frag_color;\n"
                      "#line 1\n";
    out += image;
    out += "\nvoid main() { mainImage(krs_frag_color, gl_FragCoord.xy + krs_jitter); }\n";
    return out;
}

// A built Shadertoy program and the locations of its inputs (-1 where the program does not use
// one: glUniform ignores it).
class shadertoy_program {
public:
    // Builds `image`; on failure the result is empty and `log` holds the compiler's message.
    static shadertoy_program build(const std::string& image, std::string& log)
    {
        shadertoy_program s;
        s.program_ = gl_program::build(fullscreen_triangle_vertex_shader,
                                       shadertoy_fragment_shader(image), log);
        if (!s.program_) return s;
        s.resolution_ = s.program_.uniform("iResolution");
        s.time_ = s.program_.uniform("iTime");
        s.time_delta_ = s.program_.uniform("iTimeDelta");
        s.frame_ = s.program_.uniform("iFrame");
        s.mouse_ = s.program_.uniform("iMouse");
        s.jitter_ = s.program_.uniform("krs_jitter");
        return s;
    }
    explicit operator bool() const { return bool(program_); }

    // Runs mainImage over the bound framebuffer's viewport (a vertex array must be bound).
    void draw(const shadertoy_inputs& in) const
    {
        glUseProgram(program_.id());
        glUniform3f(resolution_, in.width, in.height, 1.0f);
        glUniform1f(time_, in.time);
        glUniform1f(time_delta_, in.time_delta);
        glUniform1i(frame_, in.frame);
        glUniform4f(mouse_, in.mouse[0], in.mouse[1], in.mouse[2], in.mouse[3]);
        glUniform2f(jitter_, in.jitter[0], in.jitter[1]);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }

private:
    gl_program program_;
    GLint resolution_ = -1, time_ = -1, time_delta_ = -1, frame_ = -1, mouse_ = -1, jitter_ = -1;
};

} // namespace example
