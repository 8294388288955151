#pragma once
// The up axis of a written file. krs's scenes are y-up (a tree grows along +y, the ground is the
// plane y = 0), as glTF and OBJ expect; Blender, Houdini's VDB import and most DCC tools are z-up
// and read a PLY's or a VDB's coordinates as they are, so a y-up tree lies on its side there.
// Every writer takes an up_axis: the file's coordinates are the scene's turned by `to_file` so
// that the scene's +y lies along the file's chosen axis.
//
// up_axis::z is the rotation by +90 degrees about x: (x, y, z) -> (x, -z, y). It is proper (det
// +1), so triangles keep their winding and normals turn with the positions, and it keeps x, the
// axis both conventions share (Blender's own y-up <-> z-up conversion for glTF and OBJ is this
// one, so a file written z-up by krs and one converted by Blender agree).

#include "krs/core/vec3.hpp"

#include <array>
#include <string_view>

namespace krs {

enum class up_axis { y, z };

// The axis's name as the command lines and files spell it ("y", "z").
constexpr std::string_view up_axis_name(up_axis up) { return up == up_axis::z ? "z" : "y"; }

// The rotation from the scene's y-up frame to the file's, row-major.
constexpr std::array<double, 9> up_rotation(up_axis up)
{
    if (up == up_axis::z) return {1, 0, 0, 0, 0, -1, 0, 1, 0};
    return {1, 0, 0, 0, 1, 0, 0, 0, 1};
}

// A point or a direction of the scene in the file's frame.
template <class T>
constexpr vec3<T> to_file(up_axis up, const vec3<T>& p)
{
    return up == up_axis::z ? vec3<T>{p.x, -p.z, p.y} : p;
}

// A point or direction of the file's frame back in the scene's (the inverse rotation).
template <class T>
constexpr vec3<T> from_file(up_axis up, const vec3<T>& p)
{
    return up == up_axis::z ? vec3<T>{p.x, p.z, -p.y} : p;
}

} // namespace krs
