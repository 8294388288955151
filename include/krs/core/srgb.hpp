#pragma once
// sRGB's transfer function (IEC 61966-2-1): krs's colours are linear RGB in [0, 1] (what a
// renderer adds and scales, and glTF's COLOR_0); files whose readers take 8-bit or text colours
// as display values (PLY's uchar red green blue, OBJ's "v x y z r g b": Blender decodes both as
// sRGB) get them sRGB-encoded, so every reader lands on the same linear colour.
//
// encode: 12.92 c below 0.0031308, else 1.055 c^(1/2.4) - 0.055; decode is its inverse (the two
// pieces meet at c = 0.0031308, encoded 0.04045). Both map [0, 1] onto [0, 1], monotonically.

#include <cmath>

namespace krs {

inline double srgb_encode(double linear)
{
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
}

inline double srgb_decode(double encoded)
{
    return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

} // namespace krs
