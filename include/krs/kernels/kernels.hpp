#pragma once
// All kernel kinds krs ships, for users who do not want to pick headers one by one.

#include "krs/kernels/box.hpp"
#include "krs/kernels/capped_cone.hpp"
#include "krs/kernels/capped_cylinder.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/kernels/hexagonal_prism.hpp"
#include "krs/kernels/infinite_cylinder.hpp"
#include "krs/kernels/octahedron.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/round_box.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/tetrahedron.hpp"
#include "krs/kernels/torus.hpp"
#include "krs/kernels/torus_capsule.hpp"
