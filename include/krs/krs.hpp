#pragma once
// krs: the umbrella header. Including it gives every public piece of the library; include the
// individual headers instead to keep compile times down in large projects.

#include "krs/core/glm_interop.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"
#include "krs/core/vec3.hpp"
#include "krs/expansion.hpp"
#include "krs/field.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/mirror.hpp"
#include "krs/model/tree.hpp"
#include "krs/sequence.hpp"
#include "krs/shade/lambert.hpp"
#include "krs/shade/normal.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/located_hit.hpp"
#include "krs/trace/packet_shade.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/ray.hpp"
#include "krs/trace/sphere_trace.hpp"
#include "krs/trace/tile_prepass.hpp"
