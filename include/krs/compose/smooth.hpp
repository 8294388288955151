#pragma once
// Smooth blends of two fields: union, intersection and subtraction with a rounded seam, the
// operations of Inigo Quilez's "smooth minimum" article, each a field (krs/field.hpp).
//
// For distances a, b and a blend radius k > 0, the smooth minimum is
//     polynomial:   smin(a, b) = min(a, b) - k h^2 / 4,   h = max(k - |a - b|, 0) / k
//     exponential:  smin(a, b) = -k ln(e^(-a/k) + e^(-b/k)) = min(a, b) - k ln(1 + e^(-|a-b|/k))
// and the smooth maximum smax(a, b) = -smin(-a, -b) = max(a, b) + (the same term). The
// polynomial form equals min(a, b) wherever |a - b| >= k (the blend stays local); the exponential
// one blends everywhere, by less than k e^(-|a-b|/k). How far each moves the surface:
//     min(a, b) - k/4 <= smin_polynomial <= min(a, b),   min(a, b) - k ln 2 <= smin_exponential <= min(a, b)
// (the largest change at a = b), so a smooth union grows its solid by at most k/4 (k ln 2) and a
// smooth intersection or subtraction shrinks it by at most as much.
//
// Why each blend is still a field, with Lipschitz constant 1 (the same as its parts):
// smin is a function g(a, b) whose partial derivatives are non-negative and sum to 1, wherever
// they exist. Polynomial, for a <= b with d = b - a < k: dg/da = (k + d) / 2k and dg/db =
// (k - d) / 2k (outside the blend they are 1 and 0). Exponential: dg/da and dg/db are the weights
// e^(-a/k) / (e^(-a/k) + e^(-b/k)) and its complement. So the gradient of g(f_a(x), f_b(x)) is a
// convex combination of the parts' gradients, and its length is at most the larger of theirs: 1
// for 1-Lipschitz parts (g is continuous and piecewise smooth, so the bound holds between any two
// points, not only where g is differentiable). smax and the negated second part of a subtraction
// keep that. A 1-Lipschitz function f underestimates the distance to its own zero set: for x and
// a zero z, |f(x)| = |f(x) - f(z)| <= |x - z|. So a sphere tracer's steps stay safe, with the hit
// threshold it already has. tests/test_compose_smooth.cpp measures the constant on close pairs and
// the two forms against Quilez's mix/clamp formula and the plain log-sum-exp evaluated in double.

#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <string>
#include <string_view>
#include <utility>

namespace krs {

// The shape of the blend (the formulas above).
enum class blend_shape { polynomial, exponential };

// Which set operation a smooth blend rounds.
enum class blend_operation { unite, intersect, subtract }; // subtract: the first part minus the second

// A blend radius and shape: the radius is the width of the seam, validated at construction.
struct smooth_blend_options {
    float radius = 0.1f;
    blend_shape shape = blend_shape::polynomial;

    // How far the blend can move the surface from the hard operation's (the bounds above).
    float largest_shift() const { return shape == blend_shape::polynomial ? 0.25f * radius : 0.6931472f * radius; }
};

namespace detail {

// The term smin subtracts from min(a, b) and smax adds to max(a, b); k is the radius in lanes.
template <class T>
T blend_term(const T& a, const T& b, const T& k, blend_shape shape)
{
    const T gap = abs(a - b);
    if (shape == blend_shape::polynomial) {
        const T h = max(k - gap, T(0)) / k;
        return h * h * k * T(0.25);
    }
    return k * lane_log(T(1) + lane_exp(-gap / k));
}

} // namespace detail

// The smooth minimum and maximum of two distances (any lane type), radius k > 0.
template <class T>
T smooth_min(const T& a, const T& b, const T& k, blend_shape shape = blend_shape::polynomial)
{
    return min(a, b) - detail::blend_term(a, b, k, shape);
}
template <class T>
T smooth_max(const T& a, const T& b, const T& k, blend_shape shape = blend_shape::polynomial)
{
    return max(a, b) + detail::blend_term(a, b, k, shape);
}

// Two fields blended: smooth_blend(first, second, operation, options). The parts are any fields;
// nest blends for more than two (each nesting keeps the Lipschitz constant 1).
template <field A, field B>
class smooth_blend {
public:
    smooth_blend(A first, B second, blend_operation operation, smooth_blend_options options)
        : first_(std::move(first)), second_(std::move(second)), operation_(operation), options_(options)
    {
        // A radius of 0 would divide by zero (the polynomial's h, the exponential's gap / k); over
        // max_magnitude no scene could hold it.
        require_positive_length("smooth_blend_options.radius", options_.radius);
        if (options_.shape != blend_shape::polynomial && options_.shape != blend_shape::exponential)
            throw invalid_parameter("smooth_blend_options.shape", "must be polynomial or exponential", "another value");
        if (operation_ != blend_operation::unite && operation_ != blend_operation::intersect &&
            operation_ != blend_operation::subtract)
            throw invalid_parameter("smooth_blend operation", "must be unite, intersect or subtract", "another value");
    }

    const A& first() const { return first_; }
    const B& second() const { return second_; }
    blend_operation operation() const { return operation_; }
    const smooth_blend_options& options() const { return options_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T a = first_.distance(p);
        const T b = second_.distance(p);
        const T k = splat<T>(options_.radius);
        switch (operation_) {
        case blend_operation::unite: return smooth_min(a, b, k, options_.shape);
        case blend_operation::intersect: return smooth_max(a, b, k, options_.shape);
        case blend_operation::subtract: break;
        }
        return smooth_max(a, -b, k, options_.shape);
    }

    // GLSL (krs/glsl/emitter.hpp): the parts as NAME_a and NAME_b, NAME the blend, in the C++'s
    // order of operations (so the two agree to the rounding of GLSL's log and exp).
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(first_, name + "_a");
        out.field(second_, name + "_b");
        const std::size_t k = out.vec4({options_.radius, 0.0f, 0.0f, 0.0f}, name + " smooth blend (radius, 0, 0, 0)");
        const bool unite = operation_ == blend_operation::unite;
        const std::string b = operation_ == blend_operation::subtract ? "-" + name + "_b(x)" : name + "_b(x)";
        const std::string term = options_.shape == blend_shape::polynomial
                                     ? "    float h = max(k - gap, 0.0) / k;\n    float term = h * h * k * 0.25;\n"
                                     : "    float term = k * log(1.0 + exp(-gap / k));\n";
        out.function("float " + name + "(vec3 x) {\n"
                     "    float a = " + name + "_a(x);\n"
                     "    float b = " + b + ";\n"
                     "    float k = " + out.at(k) + ".x;\n"
                     "    float gap = abs(a - b);\n" +
                     term + (unite ? "    return min(a, b) - term;\n}\n" : "    return max(a, b) + term;\n}\n"));
    }

private:
    A first_;
    B second_;
    blend_operation operation_;
    smooth_blend_options options_;
};

// The three operations by name.
template <field A, field B>
smooth_blend<A, B> smooth_union(A first, B second, smooth_blend_options options = {})
{
    return {std::move(first), std::move(second), blend_operation::unite, options};
}
template <field A, field B>
smooth_blend<A, B> smooth_intersection(A first, B second, smooth_blend_options options = {})
{
    return {std::move(first), std::move(second), blend_operation::intersect, options};
}
// The first part with the second carved out of it.
template <field A, field B>
smooth_blend<A, B> smooth_subtraction(A first, B second, smooth_blend_options options = {})
{
    return {std::move(first), std::move(second), blend_operation::subtract, options};
}

} // namespace krs
