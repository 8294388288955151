#pragma once
// krs composition: unions of fields and their tracer (paper section 5.1), Lipschitz warps (5.2),
// placement of any field by an affine map, domain repetition, smooth blends,
// procedural bounds and empty zones (4.2, 6.4), depth composition (6.3), and wind: a field
// swaying in time by a warp whose bound holds at every instant (section 9).

#include "krs/compose/depth.hpp"
#include "krs/compose/placed.hpp"
#include "krs/compose/repeated.hpp"
#include "krs/compose/smooth.hpp"
#include "krs/compose/union.hpp"
#include "krs/compose/warp.hpp"
#include "krs/compose/wind.hpp"
#include "krs/compose/zones.hpp"
