#pragma once
// Log-polar and log-spherical warps: infinite self-similarity without loops. One header for the
// family, each concept in its own:
//
//   krs/fractal/log_tilings.hpp    log_polar_tiling, log_spherical_tiling (cells repeated at every
//                                  scale, with the bounds that keep them 1-Lipschitz)
//   krs/fractal/similar_shell.hpp  similar_shell and shell_options (one prototype shell repeated
//                                  inside and outside itself, with the seam fixes)
//   krs/fractal/shell_presets.hpp  lotus_shell, cube_shell, make_recursive_lotus,
//                                  make_cube_singularity

#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
