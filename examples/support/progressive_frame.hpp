#pragma once
// Progressive anti-aliasing (the KRS paper's "incremental image synthesis"): while nothing moves,
// every frame adds one more jittered sample of each pixel to a float texture, and the frame shown
// is their running mean, so a still view converges to the pixel-square average; any change
// (time, pointer, size, program) starts again from one sample.
//
// The samples are summed by additive blending into an RGBA32F texture (float blending is core
// since OpenGL 3.0) and a second pass writes sum / count into an RGBA8 texture: the 8-bit values a
// window shows and a screenshot reads back. One sample is x / 1 = x exactly, so a still frame's
// first sample, taken at the pixel center (jitter 0), is the program's own frame byte for byte.
// The mean is taken of the program's output as it is (already encoded for display): the viewer
// cannot know how a user's program encodes its colours.
//
// The jitter of sample k >= 1 is the Halton point (base 2, base 3) of index k, moved to
// [-1/2, 1/2)^2 of the pixel: low-discrepancy, so the mean of n samples approaches the area
// average at about 1/n rather than a random sequence's 1/sqrt(n).

#include "gl_shader.hpp"
#include "gl_window.hpp" // window_error

#include <array>
#include <cstdint>
#include <vector>

namespace example {

// The radical inverse of k in `base`: its digits mirrored behind the point, in [0, 1).
inline float radical_inverse(std::uint32_t k, std::uint32_t base)
{
    double inverse = 1.0 / double(base), scale = inverse, value = 0.0;
    for (; k > 0; k /= base, scale *= inverse)
        value += double(k % base) * scale;
    return float(value);
}

// The offset from the pixel center of sample `index` (0: the center itself).
inline std::array<float, 2> sample_jitter(std::uint32_t index)
{
    if (index == 0) return {0.0f, 0.0f};
    return {radical_inverse(index, 2) - 0.5f, radical_inverse(index, 3) - 0.5f};
}

class progressive_frame {
public:
    progressive_frame()
    {
        std::string log;
        mean_ = gl_program::build(fullscreen_triangle_vertex_shader,
                                  R"(#version 330 core
uniform sampler2D krs_sum;
uniform float krs_samples;
out vec4 krs_mean;
void main() { krs_mean = texelFetch(krs_sum, ivec2(gl_FragCoord.xy), 0) / krs_samples; }
)",
                                  log);
        if (!mean_) throw window_error("the viewer's own averaging shader failed: " + log);
        glGenVertexArrays(1, &vertex_array_);
        glGenTextures(2, textures_);
        glGenFramebuffers(2, framebuffers_);
    }
    progressive_frame(const progressive_frame&) = delete;
    progressive_frame& operator=(const progressive_frame&) = delete;
    ~progressive_frame()
    {
        glDeleteFramebuffers(2, framebuffers_);
        glDeleteTextures(2, textures_);
        glDeleteVertexArrays(1, &vertex_array_);
    }

    // Makes the textures width x height (a new size drops the samples).
    void resize(int width, int height)
    {
        if (width == width_ && height == height_) return;
        width_ = width, height_ = height;
        const GLenum formats[2] = {GL_RGBA32F, GL_RGBA8};
        for (int i = 0; i < 2; ++i) {
            glBindTexture(GL_TEXTURE_2D, textures_[i]);
            glTexImage2D(GL_TEXTURE_2D, 0, GLint(formats[i]), width, height, 0, GL_RGBA,
                         i == 0 ? GL_FLOAT : GL_UNSIGNED_BYTE, nullptr);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[i]);
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                                   textures_[i], 0);
            if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
                throw window_error(
                    "the context cannot render into an RGBA32F and an RGBA8 texture");
            glClearColor(0, 0, 0, 1); // a window shows black until a program draws
            glClear(GL_COLOR_BUFFER_BIT);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        reset();
    }
    // Drops the samples: the next one starts a new mean.
    void reset() { samples_ = 0; }
    std::uint32_t samples() const { return samples_; }
    int width() const { return width_; }
    int height() const { return height_; }

    // Adds one sample: draw(jitter) must draw it into the bound framebuffer (the sum), with the
    // jitter of this sample's index. Then writes the mean into the 8-bit frame.
    template <class Draw>
    void add_sample(Draw&& draw)
    {
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[0]);
        glViewport(0, 0, width_, height_);
        glBindVertexArray(vertex_array_);
        if (samples_ == 0) {
            glClearColor(0, 0, 0, 0);
            glClear(GL_COLOR_BUFFER_BIT);
        }
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        draw(sample_jitter(samples_));
        glDisable(GL_BLEND);
        ++samples_;

        glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[1]);
        glUseProgram(mean_.id());
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, textures_[0]);
        glUniform1i(mean_.uniform("krs_sum"), 0);
        glUniform1f(mean_.uniform("krs_samples"), float(samples_));
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    // Copies the 8-bit frame onto the window's drawable (its size in pixels), scaled to fit.
    void show(int drawable_width, int drawable_height) const
    {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffers_[1]);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        glBlitFramebuffer(0, 0, width_, height_, 0, 0, drawable_width, drawable_height,
                          GL_COLOR_BUFFER_BIT, GL_NEAREST);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    // The 8-bit frame as RGB bytes, top row first (as an image file stores it).
    std::vector<unsigned char> read_rgb() const
    {
        std::vector<unsigned char> rgba(std::size_t(width_) * std::size_t(height_) * 4);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffers_[1]);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
        std::vector<unsigned char> rgb(std::size_t(width_) * std::size_t(height_) * 3);
        for (int y = 0; y < height_; ++y) // GL's rows go bottom-up
            for (int x = 0; x < width_; ++x)
                for (int c = 0; c < 3; ++c)
                    rgb[(std::size_t(height_ - 1 - y) * std::size_t(width_) + std::size_t(x)) * 3 +
                        std::size_t(c)] =
                        rgba[(std::size_t(y) * std::size_t(width_) + std::size_t(x)) * 4 +
                             std::size_t(c)];
        return rgb;
    }

private:
    gl_program mean_;
    GLuint vertex_array_ = 0, textures_[2] = {}, framebuffers_[2] = {};
    int width_ = 0, height_ = 0;
    std::uint32_t samples_ = 0;
};

} // namespace example
