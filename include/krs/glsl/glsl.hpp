#pragma once
// GLSL emission: fields to GLSL functions (emitter.hpp) and whole Shadertoy programs (shadertoy.hpp).

#include "krs/glsl/emitter.hpp"
#include "krs/glsl/shadertoy.hpp"
