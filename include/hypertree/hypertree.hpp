#pragma once
// hypertree: volumetric IFS trees (paper "Modeling Trees with Hypertextures"). The umbrella
// header; the transforms, generator, stores and raymarcher land here as they are built. It uses
// krs's lane types and rays, never the other way round.

#include "krs/core/vec3.hpp"
#include "krs/trace/ray.hpp"
