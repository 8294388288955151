#pragma once
// hypertree: volumetric IFS trees (paper "Modeling Trees with Hypertextures"). The umbrella
// header. It uses krs's lane types, noise and rays, never the other way round.
//
// Flow: an `ifs` (C++ pipelines or a definition file) -> `generate` (seeded, deterministic) ->
// `compact` (validation: one entry per voxel) -> `density_classes` -> a store (dense, index
// list, index list + bit array, partitioned) -> operations, level of detail, rendering (CPU
// scalar or packets, or the emitted GLSL), binary save and load.

#include "hypertree/build.hpp"
#include "hypertree/create/compact.hpp"
#include "hypertree/create/density.hpp"
#include "hypertree/create/generate.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/forest.hpp"
#include "hypertree/ifs.hpp"
#include "hypertree/io/binary.hpp"
#include "hypertree/io/definition_file.hpp"
#include "hypertree/io/forest_file.hpp"
#include "hypertree/lod.hpp"
#include "hypertree/ops.hpp"
#include "hypertree/perturbation.hpp"
#include "hypertree/random.hpp"
#include "hypertree/region.hpp"
#include "hypertree/render/brick_walk.hpp"
#include "hypertree/render/glsl.hpp"
#include "hypertree/render/march_options.hpp"
#include "hypertree/render/marcher.hpp"
#include "hypertree/render/render.hpp"
#include "hypertree/render/shade_memo.hpp"
#include "hypertree/render/transfer.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "hypertree/render/voxel_shading.hpp"
#include "hypertree/store/bit_array_store.hpp"
#include "hypertree/store/dense_store.hpp"
#include "hypertree/store/index_list_store.hpp"
#include "hypertree/store/partitioned_store.hpp"
#include "hypertree/store/store.hpp"
#include "hypertree/store/store_kinds.hpp"
#include "hypertree/transform/condensation.hpp"
#include "hypertree/transform/pipeline.hpp"
#include "hypertree/volume.hpp"
#include "hypertree/voxel.hpp"
#include "krs/core/vec3.hpp"
#include "krs/trace/ray.hpp"
