#!/usr/bin/env python3
"""Writes the seed corpora of fuzz_builders.cpp and fuzz_fractals.cpp to fuzz/corpus/builders/ and
fuzz/corpus/fractals/ (fuzz_input.hpp has the byte layout). Re-run after changing the layout;
crashers found by scripts/fuzz.sh go to fuzz/crashers/<target>/ by hand."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

NAN, INF, NINF, ZERO, NZERO, FMAX = 0, 1, 2, 3, 4, 5
LIMIT, ABOVE_LIMIT, NEG_LIMIT = 12, 13, 14


def f(frac):
    """A float field at frac in [0, 1] of its valid range."""
    return bytes([0]) + struct.pack("<H", round(frac * 65535))


def below():
    return bytes([200]) + struct.pack("<H", 30000)


def above():
    return bytes([220]) + struct.pack("<H", 30000)


def special(k):
    return bytes([240 + k, 0, 0])


def i(v, lo):
    """An int field with in-range value v (range starting at lo)."""
    return bytes([v - lo])


def bad(k):
    """An invalid int: 0 bad_lo, 1 bad_hi, 2 INT_MIN, 3 INT_MAX."""
    return bytes([224 + k])


def u32(v):
    return struct.pack("<I", v)


def points(seed):
    """16 probe points: mostly near the scene (modes 0-3), then one far (4), one at the magnitude
    limit (5), one tiny (6) and the origin (7)."""
    out = b""
    for k in range(16):
        mode = [0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 4, 5, 6, 7, 2, 3][k]
        out += bytes([mode])
        for c in range(3):
            out += struct.pack("<h", ((seed * 7919 + (3 * k + c) * 104729) % 65536) - 32768)
    return out


def style(levels, over=None, ground=True):
    fields = [i(levels, 1), f(0.5), f(0.24), f(0.53), f(0.75), f(0.33), f(0.69), f(0.6), f(0.25),
              i(4, 0), f(0.3), f(0.3)]
    for k, v in (over or {}).items():
        fields[k] = v
    return b"".join(fields) + u32(levels * 17 + 3) + (bytes([1]) + f(0.5) if ground else bytes([0]))


def terrain(levels, over=None):
    fields = [i(levels, 1), f(0.4), f(0.66), f(0.15), i(3, 0), f(0.5)]
    for k, v in (over or {}).items():
        fields[k] = v
    return b"".join(fields) + u32(levels)


def vec(a, b, c):
    return f(a) + f(b) + f(c)


seeds = {
    # tree_style -> grow_tree -> build_tree
    "tree_style_default": bytes([0]) + style(8) + points(1),
    "tree_style_one_level": bytes([0]) + style(1, ground=False) + points(2),
    "tree_style_deep": bytes([0]) + style(20) + points(3),
    "tree_style_nan_length": bytes([0]) + style(6, {1: special(NAN)}) + points(4),
    "tree_style_inf_ratio": bytes([0]) + style(6, {3: special(INF)}) + points(5),
    "tree_style_bad_levels": bytes([0]) + style(6, {0: bad(1)}) + points(6),
    "tree_style_spread_above": bytes([0]) + style(6, {5: above()}) + points(7),
    # raw tree_parameters: 3 forks (2 branches, 1 inner fork)
    "tree_raw_bent": bytes([1, 3]) + vec(.5, .5, .5) + vec(.5, .7, .5) + vec(.6, .85, .5) + bytes([0])
    + vec(.52, .6, .5) + vec(.56, .8, .5) + f(.3) + f(.2) + bytes([2]) + vec(.6, .9, .5) + f(.2)
    + vec(.62, .88, .5) + f(.2) + bytes([1]) + f(.5) + points(8),
    "tree_raw_straight_fork": bytes([1, 3]) + vec(.5, .5, .5) + vec(.5, .7, .5) + vec(.5, .9, .5) + bytes([0])
    + vec(.5, .6, .5) + vec(.5, .8, .5) + f(.3) + f(.2) + bytes([0, 0]) + points(9),
    "tree_raw_one_point": bytes([1, 1]) + vec(.5, .5, .5) + bytes([0, 0, 0]) + points(10),
    "tree_raw_control_count": bytes([1, 3]) + vec(.5, .5, .5) + vec(.5, .7, .5) + vec(.6, .85, .5) + bytes([1])
    + vec(.5, .6, .5) * 3 + f(.3) * 2 + bytes([0, 0]) + points(11),
    "tree_raw_nan_fork": bytes([1, 2]) + special(NAN) + f(.5) + f(.5) + vec(.5, .7, .5) + bytes([0])
    + vec(.5, .6, .5) + f(.3) + bytes([0, 0]) + points(12),
    "tree_raw_normals": bytes([1, 4]) + vec(.5, .5, .5) + vec(.5, .7, .5) + vec(.6, .85, .5) + vec(.55, .95, .6)
    + bytes([0x40]) + vec(.5, .6, .5) + vec(.55, .8, .5) + vec(.58, .9, .55) + f(.3) + f(.2) + f(.1)
    + vec(1, .5, .5) + vec(.5, .5, 1) + bytes([0, 0]) + points(13),
    # terrain
    "terrain_default": bytes([2]) + terrain(24) + points(14),
    "terrain_one_level": bytes([2]) + terrain(1, {4: i(0, 0)}) + points(15),
    "terrain_inf_height": bytes([2]) + terrain(8, {5: special(INF)}) + points(16),
    "terrain_ratio_below": bytes([2]) + terrain(8, {2: below()}) + points(17),
    # rock
    "rock_default": bytes([3]) + vec(.5, .5, .5) + f(.2) + i(3, 1) + i(14, 0) + f(.4) + u32(1) + points(18),
    "rock_max_folds": bytes([3]) + vec(.2, .5, .9) + f(1) + i(16, 1) + i(58, 0) + f(1) + u32(7) + points(19),
    "rock_nan_center": bytes([3]) + special(NAN) + f(.5) + f(.5) + f(.2) + i(3, 1) + i(4, 0) + f(.4) + u32(1) + points(20),
    # coral
    "coral_default": bytes([4]) + i(12, 1) + f(.22) + f(.28) + f(.76) + f(.36) + f(.18) + f(.27) + u32(1) + points(21),
    "coral_max_levels": bytes([4]) + i(40, 1) + f(.5) + f(.5) + f(1) + f(1) + f(1) + f(1) + u32(9) + points(22),
    "coral_taper_nan": bytes([4]) + i(12, 1) + f(.22) + f(.28) + special(NAN) + f(.36) + f(.18) + f(.27) + u32(1) + points(23),
    # sponge
    "sponge_default": bytes([5]) + vec(.5, .5, .5) + f(.2) + i(3, 1) + points(24),
    "sponge_max_levels": bytes([5]) + vec(.3, .6, .5) + f(.8) + i(9, 1) + points(25),
    "sponge_zero_size": bytes([5]) + vec(.5, .5, .5) + special(ZERO) + i(3, 1) + points(26),
    # grass
    "grass_default": bytes([6]) + i(8, 1) + f(.3) + f(.15) + f(.35) + f(.15) + i(6, 0) + f(.025) + f(.5) + u32(1) + points(27),
    "grass_width_too_large": bytes([6]) + i(8, 1) + f(.01) + f(1) + f(.35) + f(.15) + i(2, 0) + f(.025) + f(.5) + u32(1) + points(28),
    "grass_bad_doublings": bytes([6]) + i(8, 1) + f(.3) + f(.15) + f(.35) + f(.15) + bad(1) + f(.025) + f(.5) + u32(1) + points(29),
    # forest (+ forest ground)
    "forest_default": bytes([7]) + style(5) + i(3, 0) + f(.06) + f(.22) + bytes([1]) + f(.5) + u32(1) + points(30) + bytes([0]),
    "forest_with_ground": bytes([7]) + style(4) + i(4, 0) + f(.06) + f(.22) + bytes([0]) + u32(2) + points(31)
    + bytes([1]) + terrain(10) + points(32),
    "forest_too_many_levels": bytes([7]) + style(6, {0: bad(1)}) + i(3, 0) + f(.06) + f(.22) + bytes([0]) + u32(1) + points(33),
    "forest_spacing_nan": bytes([7]) + style(3) + i(3, 0) + special(NAN) + f(.22) + bytes([0]) + u32(1) + points(34),
}

seeds["rock_at_the_limit"] = bytes([3]) + special(LIMIT) + special(ZERO) + special(ZERO) + f(.2) + i(3, 1) + i(14, 0) + f(.4) + u32(1) + points(35)
seeds["rock_near_the_limit"] = bytes([3]) + special(ZERO) + special(NEG_LIMIT) + special(ZERO) + f(0) + i(3, 1) + i(4, 0) + f(.4) + u32(1) + points(36)
seeds["tree_raw_at_the_limit"] = bytes([1, 2]) + special(LIMIT) + special(ZERO) + special(ZERO) + vec(.5, .5, .5) + bytes([0]) \
    + vec(.5, .6, .5) + f(.3) + bytes([0, 0]) + points(37)
seeds["terrain_above_the_limit"] = bytes([2]) + terrain(8, {5: special(ABOVE_LIMIT)}) + points(38)


def kifs_general(kernel, kernel_fields, iterations, taps, over=None):
    """fuzz_general_kifs: plane fold, rotation, scale, translation, then the kernel."""
    fields = [vec(1, .5, .5), f(.5), vec(.5, 1, .5), f(.55), f(.33), vec(.75, .5, .5), vec(.5, .5, .5)]
    for k, v in (over or {}).items():
        fields[k] = v
    return bytes([5]) + b"".join(fields) + bytes([kernel]) + kernel_fields + i(iterations, 0) + bytes([taps])


def shell_options(seams, cutoff=f(.04), step=f(1)):
    return bytes([seams]) + cutoff + step


fractal_seeds = {
    "square_default": bytes([0]) + i(6, 0) + f(.12) + points(101),
    "square_too_deep": bytes([0]) + bad(1) + f(.12) + points(102),
    "cube_default": bytes([1]) + i(5, 0) + points(103),
    "cube_deepest": bytes([1]) + i(20, 0) + points(104),
    "menger_default": bytes([2]) + i(4, 0) + points(105),
    "menger_deepest": bytes([2]) + i(20, 0) + points(106),
    "sierpinski_default": bytes([3]) + i(8, 0) + f(.33) + points(107),
    "sierpinski_deep_wide": bytes([3]) + i(30, 0) + f(1) + points(108),
    "sierpinski_scale_nan": bytes([3]) + i(8, 0) + special(NAN) + points(109),
    "koch_default": bytes([4]) + i(5, 0) + f(.1) + points(110),
    "koch_huge_tube": bytes([4]) + i(12, 0) + special(LIMIT) + points(111),
    "kifs_sphere": kifs_general(0, vec(.7, .5, .5) + f(.5), 8, 0) + points(112),
    "kifs_box_last": kifs_general(1, vec(.5, .5, .5) + vec(.5, .5, .5), 12, 1) + points(113),
    "kifs_capsule": kifs_general(2, vec(.4, .5, .5) + vec(.6, .5, .5) + f(.2), 10, 0) + points(114),
    "kifs_tetrahedron_deep": kifs_general(3, b"", 40, 1) + points(115),
    "kifs_torus_capsule": kifs_general(4, vec(.4, .5, .5) + vec(.6, .5, .5) + vec(.5, .6, .5) + f(.1), 10, 1)
    + points(116),
    "kifs_scale_huge": kifs_general(0, vec(.5, .5, .5) + f(.5), 20, 1, {4: special(LIMIT)}) + points(117),
    "log_polar_sphere": bytes([6]) + i(12, 1) + f(.2) + f(.3) + vec(.5, .5, .5) + bytes([1]) + f(.4) + points(118),
    "log_polar_box": bytes([6]) + i(7, 1) + f(.1) + f(.2) + vec(.5, .5, .5) + bytes([0]) + vec(.5, .5, .5) + points(119),
    "log_polar_no_cells": bytes([6]) + bad(0) + f(.2) + f(.3) + vec(.5, .5, .5) + bytes([1]) + f(.4) + points(120),
    "log_spherical_sphere": bytes([7]) + i(6, 3) + bytes([1]) + f(.3) + vec(.5, .5, .5) + bytes([1]) + f(.4) + points(121),
    "log_spherical_odd": bytes([7]) + i(6, 3) + bytes([0]) + f(.3) + vec(.5, .5, .5) + bytes([0]) + vec(.5, .5, .5)
    + points(122),
    "lotus_default": bytes([8]) + f(.044) + i(8, 1) + shell_options(1) + points(123),
    "lotus_thinnest_shells": bytes([8]) + f(0) + i(16, 1) + shell_options(0) + points(124),
    "lotus_hidden": bytes([8]) + f(.07) + i(6, 1) + shell_options(2) + points(125),
    "cube_singularity_default": bytes([9]) + f(.044) + shell_options(1) + points(126),
    "cube_singularity_density_below": bytes([9]) + below() + shell_options(1) + points(127),
    "user_shell_sphere": bytes([10]) + f(.02) + vec(.7, .5, .5) + f(.2) + shell_options(1) + points(128),
    "user_shell_off_prototype": bytes([10]) + f(.5) + vec(1, 1, 1) + f(1) + shell_options(0) + points(129),
}

for target, table in (("builders", seeds), ("fractals", fractal_seeds)):
    out = os.path.join(HERE, "corpus", target)
    os.makedirs(out, exist_ok=True)
    for name, data in table.items():
        with open(os.path.join(out, name), "wb") as fh:
            fh.write(data)
    print(f"wrote {len(table)} seeds to {out}")
