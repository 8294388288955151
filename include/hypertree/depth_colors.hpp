#pragma once
// Colors from voxel depth (paper section 8.3, DEPTHCOLOR of section 10): ranges of depths map to
// color spans, e.g. branches brown, leaves green from dark to light, fruit red. A depth outside
// every range takes the nearest range's end color.

#include "krs/core/validate.hpp"

#include <string>
#include <vector>

namespace hypertree {

struct rgb {
    float r = 0, g = 0, b = 0;
};

// A color's channels finite and non-negative (a NaN or negative one reaches the pixels as it is).
inline void require_color(const char* name, const rgb& c)
{
    krs::require_non_negative(name, c.r);
    krs::require_non_negative(name, c.g);
    krs::require_non_negative(name, c.b);
}

struct depth_color_span {
    int from = 0, to = 0; // depths, inclusive
    rgb first, last;      // colors at `from` and `to`, interpolated between
};

class depth_colors {
public:
    depth_colors() = default;
    explicit depth_colors(std::vector<depth_color_span> spans) : spans_(std::move(spans))
    {
        for (std::size_t i = 0; i < spans_.size(); ++i) {
            if (spans_[i].from > spans_[i].to || spans_[i].from < 0)
                throw krs::invalid_parameter("depth_colors[" + std::to_string(i) + "]", "needs 0 <= from <= to",
                                             std::to_string(spans_[i].from) + ".." + std::to_string(spans_[i].to));
            require_color("depth_colors.first", spans_[i].first);
            require_color("depth_colors.last", spans_[i].last);
        }
    }
    // Branches (depth <= branch_depth) bark brown; leaves from dark to light green.
    static depth_colors tree(int branch_depth, int tree_depth)
    {
        return depth_colors({{0, branch_depth, {0.30f, 0.20f, 0.11f}, {0.36f, 0.25f, 0.14f}},
                             {branch_depth + 1, std::max(branch_depth + 1, tree_depth - 1), {0.16f, 0.34f, 0.08f}, {0.45f, 0.66f, 0.20f}}});
    }

    rgb at(int depth) const
    {
        if (spans_.empty()) return {0.5f, 0.5f, 0.5f};
        const depth_color_span* nearest = &spans_.front();
        int best = 1 << 30;
        for (const auto& s : spans_) {
            if (depth >= s.from && depth <= s.to) return interpolate(s, depth);
            const int gap = depth < s.from ? s.from - depth : depth - s.to;
            if (gap < best) best = gap, nearest = &s;
        }
        return depth < nearest->from ? nearest->first : nearest->last;
    }
    const std::vector<depth_color_span>& spans() const { return spans_; }

private:
    static rgb interpolate(const depth_color_span& s, int depth)
    {
        const float t = s.to == s.from ? 0.0f : float(depth - s.from) / float(s.to - s.from);
        return {s.first.r + (s.last.r - s.first.r) * t, s.first.g + (s.last.g - s.first.g) * t, s.first.b + (s.last.b - s.first.b) * t};
    }
    std::vector<depth_color_span> spans_;
};

} // namespace hypertree
