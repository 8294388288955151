#pragma once
// krs composition: unions of fields and their tracer (paper section 5.1), Lipschitz warps (5.2),
// placement of any field by an affine map, domain repetition, smooth blends,
// procedural bounds and empty zones (4.2, 6.4), and depth composition (6.3).

#include "krs/compose/depth.hpp"
#include "krs/compose/placed.hpp"
#include "krs/compose/repeated.hpp"
#include "krs/compose/smooth.hpp"
#include "krs/compose/union.hpp"
#include "krs/compose/warp.hpp"
#include "krs/compose/zones.hpp"
