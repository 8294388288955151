#!/usr/bin/env python3
"""Writes the seed corpora of fuzz_builders.cpp and fuzz_fractals.cpp to fuzz/corpus/builders/ and
fuzz/corpus/fractals/ (fuzz_input.hpp has the byte layout), and those of fuzz_definition.cpp and
fuzz_binary.cpp to fuzz/corpus/definition/ and fuzz/corpus/binary/ (layouts in those files).
Re-run after changing a layout; crashers found by scripts/fuzz.sh go to fuzz/crashers/<target>/ by hand."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def write_corpora(*targets):
    """Writes each (target, {name: bytes}) table as the files of corpus/<target>/."""
    for target, table in targets:
        out = os.path.join(HERE, "corpus", target)
        os.makedirs(out, exist_ok=True)
        for name, data in table.items():
            with open(os.path.join(out, name), "wb") as fh:
                fh.write(data)
        print(f"wrote {len(table)} seeds to {out}")

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


def shell_options(seams, cutoff=f(.04), step=f(1), band=f(0)):
    return bytes([seams]) + cutoff + step + band


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
    "lotus_hidden_local_step": bytes([8]) + f(.044) + i(8, 1) + shell_options(2, step=f(.47), band=f(.12)) + points(130),
    "cube_singularity_band_above": bytes([9]) + f(.044) + shell_options(0, band=above()) + points(131),
    "cube_singularity_default": bytes([9]) + f(.044) + shell_options(1) + points(126),
    "cube_singularity_density_below": bytes([9]) + below() + shell_options(1) + points(127),
    "user_shell_sphere": bytes([10]) + f(.02) + vec(.7, .5, .5) + f(.2) + shell_options(1) + points(128),
    "user_shell_off_prototype": bytes([10]) + f(.5) + vec(1, 1, 1) + f(1) + shell_options(0) + points(129),
}

write_corpora(("builders", seeds), ("fractals", fractal_seeds))


# fuzz_definition.cpp: the input is a definition or forest file's text, unchanged. Seeds: the
# example files, then small trees that each use one feature, and a few refusals.
EXAMPLES = os.path.join(HERE, "..", "examples", "hypertrees")
definition_seeds = {}
for example in sorted(os.listdir(EXAMPLES)):
    if not os.path.isfile(os.path.join(EXAMPLES, example)):  # figure09_quarters/: a folder of trees
        continue
    with open(os.path.join(EXAMPLES, example), "rb") as fh:
        definition_seeds["example_" + example.replace(".", "_")] = fh.read()


def small_tree(body, head="RESOLUTION 12\nITERATIONS 300\nTREEDEPTH 5\n"):
    return (head + body).encode()


ONE_STEM = "CONDENSATION\n  CONE y 0 0.5 0.03 0.015\n"
BRANCH = "TRANSFORM 1 0\n  SCALE 0.6\n  ROTATE 0 0 1 35\n  TRANSLATE 0 0.4 0\n"
definition_seeds.update({
    "tree_minimal": small_tree(BRANCH),
    "tree_per_level": small_tree(ONE_STEM + "TRANSFORM 1 0\n  SCALE (0.6, 0.5)\n  ROTATE 0 0 1 (40, 30, 20)\n"
                                 "  TRANSLATE 0 (0.4, 0.3, 0.2) 0\n"),
    "tree_random": small_tree(ONE_STEM + "TRANSFORM 1 0\n  SCALE 0.55~0.05\n  ROTATE 0 1 0 137~20\n"
                              "  ROTATE 0 0 1 (40~5, 30~2)\n  TRANSLATE 0 0.4~0.05 0\n"),
    "tree_dummy": small_tree(ONE_STEM + BRANCH + "TRANSFORM 0.5 3 DUMMY 1\n  SCALE 0.4\n  TRANSLATE 0.1 0.3 0\n"),
    "tree_lineinit": small_tree("LINEINIT 0 0 0 0 0.05 0\n" + ONE_STEM + BRANCH),
    "tree_perturb": small_tree("PERTURB 0.01 0.02 0.01 6\n" + ONE_STEM + BRANCH),
    "tree_two_condensations": small_tree(
        "CONDENSATION\n  CONE y 0 0.5 0.03 0.015\n  SHEAR y 0.12 0 2 0.5\n"
        "CONDENSATION\n  CONE y 0 0.5 0.03 0.015\n  SHEAR y -0.12 0.03 2 0.5\n"
        "  ROTATE 0 1 0 90\n" + "TRANSFORM 1 0\n  SHEAR x 0.05 0 2\n  SCALE (0.5, 0.46, 0.44)\n  TRANSLATE 0 0.3 0\n"),
    "tree_everything": small_tree(
        'NAME "all keywords"\nBRANCHDEPTH 2\nDENSITYCLASSES 8\nHYPERVOLUME 1 1.2 1\nDISPLACEMENT 0.5 0 0.5\n'
        "POINTINIT 0 0.01 0\nDEPTHCOLOR 0 2 0.3 0.2 0.1 0.4 0.3 0.2\nDEPTHCOLOR 3 4 0.1 0.5 0.1 0.2 0.7 0.2\n"
        + ONE_STEM + "  TRANSLATE 0 0.01 0\n" + BRANCH + "TRANSFORM 2 4\n  SCALE 0.5 0.45 0.5\n  ROTATE 1 0 1 -30\n"
        "  SHEAR z 0.02 0.01 1.5 0.8\n  TRANSLATE 0 0.3 0\n", head="RESOLUTION 10 14 12\nITERATIONS 250\nTREEDEPTH 6\n"),
    "tree_crlf_tabs_comments": small_tree(BRANCH).replace(b"\n", b"  # note\r\n").replace(b"  ", b"\t"),
    "tree_deepest": small_tree(BRANCH, head="RESOLUTION 8\nITERATIONS 200\nTREEDEPTH 64\nBRANCHDEPTH 63\n"),
    "tree_limits": small_tree("PERTURB 1e9 -1e9 0 1e9\n" + BRANCH.replace("0.4", "1e9"),
                              head="RESOLUTION 1 2 2147483647\nITERATIONS 18446744073709551615\nTREEDEPTH 2\n"),
    "refused_not_contraction": small_tree("TRANSFORM 1 0\n  SCALE 1.5\n"),
    "refused_unknown_keyword": small_tree("GROW 1\n" + BRANCH),
    "refused_unterminated_quote": small_tree('NAME "no end\n' + BRANCH),
    "refused_too_many_voxels": small_tree(BRANCH, head="RESOLUTION 65536 65536 2\n"),
    "forest_small": b"RESOLUTION 32 16 32\nSTORAGETYPE partitioned\nTREE a.tree\nTREE \"b c.tree\" 1 0 -1\n"
                    b"TREE /abs/d.tree -1e9 0 1e9\n",
    "forest_refused_storage": b"RESOLUTION 8\nSTORAGETYPE octree\nTREE a.tree\n",
    # Files as editors save them (issue 37): old Mac line endings (CR only), a UTF-8 byte-order
    # mark, both, a lone CR inside quoted text, UTF-16 and UTF-32 (refused by name), and each kind
    # of file given as the other (named by its first keyword only the other kind has).
    "tree_cr_only": small_tree(ONE_STEM + BRANCH + 'NAME "a name"  # a comment\n').replace(b"\n", b"\r"),
    "tree_bom": b"\xef\xbb\xbf" + small_tree(ONE_STEM + BRANCH),
    "tree_bom_cr_mixed": b"\xef\xbb\xbf" + small_tree(ONE_STEM + BRANCH).replace(b"\n", b"\r", 3),
    "refused_cr_in_quote": small_tree('NAME "split\rhere"\n' + BRANCH),
    "refused_quote_open_at_line_end": small_tree('NAME "open\nNAME "closed"\n' + BRANCH),
    "refused_utf16": b"\xff\xfe" + small_tree(BRANCH).decode().encode("utf-16-le"),
    "refused_utf16_big_endian": b"\xfe\xff" + small_tree(BRANCH).decode().encode("utf-16-be"),
    "refused_utf32": b"\xff\xfe\x00\x00" + small_tree(BRANCH).decode().encode("utf-32-le"),
    "refused_forest_as_tree": b"RESOLUTION 8\nSTORAGETYPE dense\nTREE other.forest\n",
    "forest_cr_only_bom": b"\xef\xbb\xbfRESOLUTION 8\rSTORAGETYPE dense\rTREE a.tree 1 0 0\r",
    "forest_refused_tree_keyword": b"RESOLUTION 8\nTREEDEPTH 4\nSTORAGETYPE dense\nTREE a.tree\n",
})


# fuzz_binary.cpp: byte 0 selects the store kind (bits 0-1), recomputing the checksum (bit 2) and
# a byte after the file (bit 3); the rest is a saved tree, written here by an independent writer
# of the format of include/hypertree/io/binary.hpp (so the ctest replay also checks that the
# loader reads files it did not write).
def fnv1a64(data):
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def saved_tree(origin, extent, grid, voxels, count=None, version=1):
    """voxels: (index, density, level, part), sorted by index."""
    body = b"KRSHTREE" + struct.pack("<I", version) + struct.pack("<3d", *origin) + struct.pack("<3d", *extent)
    body += struct.pack("<3i", *grid) + struct.pack("<Q", len(voxels) if count is None else count)
    for index, density, level, part in voxels:
        body += struct.pack("<IBBB", index, density, level, part)
    return body + struct.pack("<Q", fnv1a64(body))


def grown_tree(n):
    """A trunk up the middle of an n^3 grid and two branches to the sides, levels and parts as the
    generator gives them (trunk: level 0, part 0; branch j: part j + 1)."""
    cells = {}
    mid = n // 2
    for y in range(n * 2 // 3):
        cells[(mid, y, mid)] = (255, 0, 0)
    for j, dx in enumerate((1, -1)):
        for k in range(1, n // 3):
            x, y = mid + dx * k, n // 3 + k
            cells[(x, y, mid)] = (255 if k < 3 else 40 + 50 * (k % 4), 1 if k < 3 else 2, j + 1)
    voxels = [(x + n * (y + n * z), d, l, p) for (x, y, z), (d, l, p) in cells.items()]
    return sorted(voxels)


unit = ((-0.75, -0.01, -0.75), (1.5, 1.21, 1.5))
binary_seeds = {}
for kind, name in enumerate(("dense", "index_list", "bit_array", "partitioned")):
    binary_seeds[f"tree12_{name}"] = bytes([kind]) + saved_tree(*unit, (12, 12, 12), grown_tree(12))
binary_seeds.update({
    "tree16_index_list_trailing_byte": bytes([8 | 1]) + saved_tree(*unit, (16, 16, 16), grown_tree(16)),
    "tree8_partitioned_fixed_checksum": bytes([4 | 3]) + saved_tree(*unit, (8, 8, 8), grown_tree(8)),
    "empty_tree": bytes([1]) + saved_tree((0, 0, 0), (1, 1, 1), (4, 4, 4), []),
    "one_voxel_last_index": bytes([2]) + saved_tree((0, 0, 0), (1, 1, 1), (4, 4, 4), [(63, 1, 7, 254)]),
    "flat_grid": bytes([3]) + saved_tree((-5, 0, 2), (10, 0.1, 1e-3), (16, 1, 3),
                                         [(i, 1 + i * 5, i % 3, i % 4) for i in range(0, 48, 3)]),
    "huge_grid_few_voxels": bytes([1]) + saved_tree((0, 0, 0), (1e6, 1e6, 1e6), (65535, 65535, 1),
                                                    [(0, 9, 0, 0), (4294836224, 9, 1, 1)]),
    "huge_grid_dense_over_budget": bytes([0]) + saved_tree((0, 0, 0), (1, 1, 1), (4096, 4096, 16), [(5, 3, 0, 0)]),
    "claims_many_voxels": bytes([1 | 4]) + saved_tree(*unit, (12, 12, 12), grown_tree(12)[:3], count=1728),
    "bad_checksum": bytes([1]) + saved_tree(*unit, (12, 12, 12), grown_tree(12))[:-1] + b"\0",
    "unsorted_voxels": bytes([1 | 4]) + saved_tree(*unit, (12, 12, 12), [(9, 4, 0, 0), (3, 4, 0, 0)]),
    "version_2": bytes([1]) + saved_tree(*unit, (12, 12, 12), grown_tree(12)[:4], version=2),
    "truncated_header": bytes([1]) + saved_tree(*unit, (12, 12, 12), [])[:50],
})

write_corpora(("definition", definition_seeds), ("binary", binary_seeds))
