#!/usr/bin/env python3
"""Regenerates docs/benchmarks.md (and its SVG plots in docs/images/) from benchmark CSVs.

    scripts/benchmark_report.py BUILD_DIR [--docs DOCS_DIR]

Looks in BUILD_DIR and BUILD_DIR/bench for the CSVs the benchmarks write:

    bench_packet_trace.csv      KRS packet tracer (sections keyed by the first column, each
                                introduced by a header row whose first field is "table")
    bench_packet_trace_avx2.csv the same with 8-lane packets (its throughput table)
    bench_hypertree_create.csv  hypertree creation and memory (paper Table 1)
    bench_hypertree_render.csv  hypertree rendering (paper Table 1) and speed against error
    bench_openvdb_peer.csv      the hypertree stores against OpenVDB grids
    bench_embree_peer.csv       KRS against Embree (optional: any columns named n, *mrays*,
                                and memory / bytes are plotted; a missing file is reported)

A CSV that is absent gives a sentence saying so, never an error. The plots are SVG written here
by hand (no plotting library, so the report adds no dependency). The machine section describes
the computer this script runs on: run it where the benchmarks ran.
"""

import argparse
import csv
import datetime
import html
import math
import os
import platform
import re
import subprocess
import sys

# ---- reading -------------------------------------------------------------------------------------


def find_csv(build, name):
    for folder in (build, os.path.join(build, "bench")):
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            return path
    return None


def read_rows(path):
    """A plain CSV: a list of dicts."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_sections(path):
    """A CSV of several tables: a header row starts with "table"; it names the columns of the
    rows right after it, whose first field is the section's name. Rows of a section that had no
    header of its own get columns c1, c2, ..."""
    sections, header, bound = {}, None, set()
    with open(path, newline="") as f:
        for fields in csv.reader(f):
            if not fields:
                continue
            if fields[0] == "table":
                header = fields
                continue
            name = fields[0]
            if header is not None and name not in bound and name not in sections:
                columns = header
                bound.add(name)
                header = None
            elif name in sections and sections[name]["columns"] is not None:
                columns = sections[name]["columns"]
            else:
                columns = ["table"] + ["c%d" % i for i in range(1, len(fields))]
            section = sections.setdefault(name, {"columns": columns, "rows": []})
            section["rows"].append(dict(zip(columns, fields)))
    return {k: v["rows"] for k, v in sections.items()}


def num(value, default=None):
    try:
        v = float(value)
        return v if math.isfinite(v) else default
    except (TypeError, ValueError):
        return default


# ---- formatting ----------------------------------------------------------------------------------


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    return "\n".join(out) + "\n"


def fmt(v, digits=3):
    if v is None:
        return "-"
    if v == 0:
        return "0"
    a = abs(v)
    if a >= 1000:
        return "%.0f" % v
    return ("%." + str(digits) + "g") % v


def mib(b):
    return None if b is None else b / 2**20


def size_text(b):
    if b is None:
        return "-"
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if b >= scale:
            return "%.2f %s" % (b / scale, unit)
    return "%d B" % b


# ---- SVG plots -----------------------------------------------------------------------------------

COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#17becf", "#bcbd22"]


def nice_ticks(lo, hi, log):
    if log:
        a, b = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
        return [10.0**e for e in range(a, b + 1)]
    if hi <= lo:
        hi = lo + 1
    raw = (hi - lo) / 5
    step = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if raw <= m * step:
            step *= m
            break
    start = math.floor(lo / step) * step
    ticks, t = [], start
    while t <= hi + step * 0.5:
        ticks.append(round(t, 12))
        t += step
    return ticks


def svg_chart(path, title, xlabel, ylabel, series, logx=False, logy=False, markers_only=False):
    """series: list of (name, [(x, y), ...]). Writes an SVG line chart; returns True if drawn."""
    series = [(n, [(x, y) for x, y in pts if x is not None and y is not None and (not logx or x > 0) and (not logy or y > 0)])
              for n, pts in series]
    series = [(n, sorted(p)) for n, p in series if p]
    if not series:
        return False
    xs = [x for _, p in series for x, _ in p]
    ys = [y for _, p in series for _, y in p]
    xt = nice_ticks(min(xs), max(xs), logx)
    yt = nice_ticks(min(ys) if logy else min(0.0, min(ys)), max(ys), logy)
    x0, x1, y0, y1 = xt[0], xt[-1], yt[0], yt[-1]
    if x1 == x0:
        x1 = x0 + 1
    if y1 == y0:
        y1 = y0 + 1
    W, H, L, R, T, B = 720, 420, 80, 220, 40, 55

    def px(x):
        f = (math.log10(x) - math.log10(x0)) / (math.log10(x1) - math.log10(x0)) if logx else (x - x0) / (x1 - x0)
        return L + f * (W - L - R)

    def py(y):
        f = (math.log10(y) - math.log10(y0)) / (math.log10(y1) - math.log10(y0)) if logy else (y - y0) / (y1 - y0)
        return H - B - f * (H - T - B)

    e = html.escape
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
           'font-family="sans-serif" font-size="12">' % (W, H, W, H),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="22" font-size="15" font-weight="bold">%s</text>' % (L, e(title))]
    for t in xt:
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (px(t), T, px(t), H - B))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (px(t), H - B + 16, e(fmt(t))))
    for t in yt:
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (L, py(t), W - R, py(t)))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (L - 6, py(t) + 4, e(fmt(t))))
    out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#333"/>' % (L, T, W - L - R, H - T - B))
    out.append('<text x="%d" y="%d" text-anchor="middle">%s%s</text>' % ((L + W - R) / 2, H - 12, e(xlabel), " (log)" if logx else ""))
    out.append('<text transform="translate(18 %d) rotate(-90)" text-anchor="middle">%s%s</text>' % ((T + H - B) / 2, e(ylabel),
                                                                                                   " (log)" if logy else ""))
    for i, (name, pts) in enumerate(series):
        c = COLORS[i % len(COLORS)]
        coords = " ".join("%.1f,%.1f" % (px(x), py(y)) for x, y in pts)
        if not markers_only and len(pts) > 1:
            out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (coords, c))
        for x, y in pts:
            out.append('<circle cx="%.1f" cy="%.1f" r="3.5" fill="%s"><title>%s: %s, %s</title></circle>' % (px(x), py(y), c, e(name),
                                                                                                            fmt(x), fmt(y)))
        ly = T + 8 + 18 * i
        out.append('<rect x="%d" y="%d" width="14" height="4" fill="%s"/>' % (W - R + 12, ly, c))
        out.append('<text x="%d" y="%d">%s</text>' % (W - R + 32, ly + 6, e(name[:30])))
    out.append("</svg>")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return True


# ---- the machine ---------------------------------------------------------------------------------


def machine():
    model, flags = "unknown", set()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                key = key.strip()
                if key == "model name" and model == "unknown":
                    model = value.strip()
                elif key == "flags" and not flags:
                    flags = set(value.split())
    except OSError:
        pass
    isa = [f for f in ("sse4_2", "avx", "avx2", "fma") if f in flags] + sorted(f for f in flags if f.startswith("avx512"))
    compiler = ""
    try:
        compiler = subprocess.run(["c++", "--version"], capture_output=True, text=True, timeout=10).stdout.splitlines()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        pass
    load = "%.1f %.1f %.1f" % os.getloadavg() if hasattr(os, "getloadavg") else "-"
    return {"cpu": model, "cores": os.cpu_count() or 0, "isa": " ".join(isa) or "unknown", "os": platform.platform(), "compiler": compiler,
            "load": load}


# ---- sections ------------------------------------------------------------------------------------


def packet_width_section(path, md):
    """The 8-lane build's scalar-against-packet table (bench_packet_trace_avx2), when it was run."""
    if not path:
        return
    rows = read_sections(path).get("throughput", [])
    if not rows:
        return
    md.append("\nThe same with 8-lane packets (`bench_packet_trace_avx2`, AVX2; scalar code built the same way):\n")
    md.append(table(["scene", "threads", "scalar Mrays/s", "packet Mrays/s", "packet/scalar", "lanes busy"],
                    [[r.get("scene"), r.get("threads"), fmt(num(r.get("scalar_mrays_s"))), fmt(num(r.get("packet_mrays_s"))),
                      fmt(num(r.get("ratio"))) + "x", "%.1f%%" % (100 * num(r.get("lane_utilization"), 0))] for r in rows]))


def packet_trace_section(path, images, md):
    md.append("## KRS packet tracer (`bench_packet_trace`)\n")
    if not path:
        md.append("_bench_packet_trace.csv not found: run `bench/bench_packet_trace` in the build directory._\n")
        return {}, {}
    s = read_sections(path)
    rows = s.get("throughput", [])
    if rows:
        md.append("Primary rays, scalar against packet path (16-ray packets where the build has 16 lanes):\n")
        md.append(table(["scene", "threads", "scalar Mrays/s", "packet Mrays/s", "packet/scalar", "lanes busy", "evals/ray"],
                        [[r.get("scene"), r.get("threads"), fmt(num(r.get("scalar_mrays_s"))), fmt(num(r.get("packet_mrays_s"))),
                          fmt(num(r.get("ratio"))) + "x", "%.1f%%" % (100 * num(r.get("lane_utilization"), 0)),
                          fmt(num(r.get("evals_per_ray")))] for r in rows]))
    levels = s.get("levels", [])
    if levels:
        md.append("\nTime per ray against the expansion level n (paper section 8; 1 thread):\n")
        md.append(table(["n", "tree scalar us", "tree packet us", "terrain scalar us", "terrain packet us",
                         "axis terrain scalar us", "axis terrain packet us"],
                        [[r.get("n"), r.get("tree_scalar_us"), r.get("tree_packet_us"), r.get("terrain_scalar_us"),
                          r.get("terrain_packet_us"), r.get("terrain_axis_scalar_us", "-"),
                          r.get("terrain_axis_packet_us", "-")] for r in levels]))
    slopes = s.get("levels_slope", [])
    if slopes:
        md.append("\nLeast-squares line time per ray = fixed + slope n, its R^2, the fixed cost in levels (fixed / slope), and "
                  "time(32) / time(16), which is at most 1.5 exactly when the fixed cost is at least 16 levels:\n")
        md.append(table(["path", "us per level", "fixed us", "R^2", "fixed cost in levels", "time(32)/time(16)"],
                        [[r.get("path"), r.get("us_per_level"), r.get("fixed_us"), r.get("r2"), r.get("fixed_in_levels"),
                          r.get("time_32_over_16")]
                         for r in slopes]))
    error = s.get("error", [])
    if error:
        series = {}
        for r in error:
            key = "%s px, %s" % (r.get("threshold_px"), "prepass" if r.get("prepass") == "1" else "plain")
            series.setdefault(key, []).append((num(r.get("mean_relative_depth_error")), num(r.get("ns_per_ray"))))
        if svg_chart(os.path.join(images, "krs_speed_error.svg"), "KRS: time per ray against depth error (forest, 2 threads)",
                     "mean relative depth error", "ns per ray", sorted(series.items()), markers_only=True):
            md.append("\nSpeed against error (forest of 64 trees; each point one setting of omega and step cap):\n")
            md.append("![KRS speed against error](images/krs_speed_error.svg)\n")
        md.append("\n" + table(["threshold px", "omega", "prepass", "max steps", "ns/ray", "evals/ray", "rel. depth error",
                                "hit/miss differ"],
                               [[r.get("threshold_px"), r.get("omega"), r.get("prepass"), r.get("max_steps"), r.get("ns_per_ray"),
                                 r.get("evals_per_ray"), r.get("mean_relative_depth_error"),
                                 "%.3f%%" % (100 * num(r.get("hit_miss_differ_share"), 0))] for r in error]))
    shadows = s.get("shadows", [])
    if shadows:
        md.append("\n### Soft shadows and ambient occlusion in packets (issue 23, item 3)\n")
        md.append("`soft_shadow` and `ambient_occlusion` are one template for a ray and a packet (the shadow marches "
                  "on the tracers' `march_state` / `march_step`, its penumbra ratio in the step's observer). Shading "
                  "points: the primary hits of each scene's camera in 8 x 8 tile order, with their kernels' normals; "
                  "a shadow ray toward krs_scenes' sun from each point facing it (hardness 12, 160 steps), a 5-sample "
                  "occlusion probe from every point. One thread, scalar and packet rounds alternating, best of R each "
                  "(`bench_packet_trace --only shadows`). \"previous scalar\" is the soft shadow's own loop from "
                  "before it ran on the march step, kept in the benchmark (it returns the same value as the scalar "
                  "call on every ray here). \"max diff\" is the largest |packet lane - scalar call| "
                  "and \"differ\" the lanes not bit-identical; the benchmark is built with g++'s default "
                  "-ffp-contract=fast, under which the two paths may fuse a * b + c differently (the tests, built "
                  "with it off, require every lane bit-identical).\n")
        md.append(table(["scene", "shadow rays", "penumbra", "previous scalar Mrays/s", "scalar Mrays/s",
                         "packet Mrays/s", "packet/scalar", "max diff", "differ", "AO probes", "scalar Mprobes/s",
                         "packet Mprobes/s", "packet/scalar", "max diff", "differ"],
                        [[r.get("scene"), r.get("shadow_rays"),
                          "%.1f%%" % (100 * num(r.get("penumbra_rays"), 0) / max(num(r.get("shadow_rays"), 1), 1)),
                          fmt(num(r.get("shadow_previous_scalar_mrays_s"))),
                          fmt(num(r.get("shadow_scalar_mrays_s"))), fmt(num(r.get("shadow_packet_mrays_s"))),
                          fmt(num(r.get("shadow_ratio"))) + "x", r.get("shadow_max_lane_difference"),
                          r.get("shadow_lanes_differ"), r.get("ao_probes"), fmt(num(r.get("ao_scalar_mprobes_s"))),
                          fmt(num(r.get("ao_packet_mprobes_s"))), fmt(num(r.get("ao_ratio"))) + "x",
                          r.get("ao_max_lane_difference"), r.get("ao_lanes_differ")] for r in shadows]))
        for r in s.get("shadows_load", []):
            md.append("\nLoad average before: %s; after: %s.\n" % (r.get("before"), r.get("after")))
    # Mrays/s against n from the levels table (1 thread): 1 / (us per ray); and the sequences' own
    # memory per n (bytes, as MiB like the Embree side), when the CSV has it.
    krs = series_against_n(levels, (("tree_packet_us", "KRS tree packet (1 thread)"),
                                    ("terrain_packet_us", "KRS terrain packet (1 thread)")), lambda us: 1.0 / us)
    krs_memory = series_against_n(levels, (("tree_memory_bytes", "KRS tree"), ("terrain_memory_bytes", "KRS terrain")),
                                  lambda b: b / 2.0 ** 20)
    return krs, krs_memory


def series_against_n(rows, columns, convert):
    """{name: [(n, convert(value))]} for each (column, name), skipping missing or zero values."""
    series = {}
    for r in rows:
        n = num(r.get("n"))
        for col, name in columns:
            v = num(r.get(col))
            if n is not None and v:
                series.setdefault(name, []).append((n, convert(v)))
    return series


def embree_section(path, krs_series, krs_memory, images, md):
    md.append("## KRS against Embree (`bench_embree_peer`)\n")
    series_rays, series_memory = dict(krs_series), dict(krs_memory)
    if not path:
        md.append("_bench_embree_peer.csv not found (build with the Embree option and run `bench/bench_embree_peer`); "
                  "only the KRS side is plotted._\n")
    else:
        rows = read_rows(path)
        columns = list(rows[0].keys()) if rows else []
        ncol = next((c for c in columns if c.strip().lower() == "n"), None)
        rays = [c for c in columns if "mrays" in c.lower()]
        memory = [c for c in columns if re.search(r"mem|bytes|mib|gib", c, re.I)]
        groups = [c for c in columns if c.lower() in ("config", "configuration", "renderer", "method", "mode", "variant", "layout",
                                                      "tracer", "peer", "scene", "packet", "rays")]
        md.append(table(columns, [[r.get(c, "") for c in columns] for r in rows]))
        for r in rows:
            n = num(r.get(ncol)) if ncol else None
            label = " ".join(r.get(g, "") for g in groups).strip() or "Embree"
            for c in rays:
                series_rays.setdefault("%s %s" % (label, c) if len(rays) > 1 else label, []).append((n, num(r.get(c))))
            for c in memory:
                scale = 1.0 if re.search(r"mib", c, re.I) else 1024.0 if re.search(r"gib", c, re.I) else 1.0 / 2**20
                v = num(r.get(c))
                series_memory.setdefault("%s %s" % (label, c) if len(memory) > 1 else label, []).append((n, None if v is None else v * scale))
    if svg_chart(os.path.join(images, "rays_against_n.svg"), "Primary rays per second against expansion level n", "n", "Mrays/s",
                 sorted(series_rays.items()), logy=True):
        md.append("\n![rays/s against n](images/rays_against_n.svg)\n")
    if series_memory and svg_chart(os.path.join(images, "memory_against_n.svg"), "Memory against expansion level n", "n", "MiB",
                                   sorted(series_memory.items()), logy=True):
        md.append("\n![memory against n](images/memory_against_n.svg)\n")
    elif not series_memory:
        md.append("\n_Memory against n: no memory column to plot yet (the Embree peer's CSV brings it)._\n")


def create_section(path, md):
    md.append("## Hypertree creation and memory next to the paper's Table 1 (`bench_hypertree_create`)\n")
    if not path:
        md.append("_bench_hypertree_create.csv not found._\n")
        return
    rows = read_rows(path)
    body = []
    ms = lambda v: "%.1f ms" % (1e3 * v) if v is not None else "-"
    faults = lambda v: "%.0f" % v if v is not None else "-"
    ratio = lambda p, t: ("%.0fx" % (p / t)) if p and t else "-"
    for r in rows:
        c, pc = num(r.get("creation_s")), num(r.get("paper_creation_s"))
        f, k4 = num(r.get("fresh_s")), num(r.get("small_pages_s"))
        m, pm = num(r.get("memory_bytes")), num(r.get("paper_memory_bytes"))
        spread = num(r.get("creation_spread"))
        if r.get("memory_bytes", "").strip() == "refused":
            body.append([r.get("tree"), r.get("resolution"), r.get("store"), r.get("voxels"), "refused: over the memory budget"]
                        + ["-"] * 16)
            continue
        build = "%s (%s) / %s (%s)" % (ms(num(r.get("build_s"))), faults(num(r.get("build_faults"))), ms(num(r.get("rebuild_s"))),
                                       faults(num(r.get("rebuild_faults"))))
        before = num(r.get("before_s"))
        body.append([r.get("tree"), r.get("resolution"), r.get("store"), r.get("voxels"), build, ms(c), faults(num(r.get("creation_faults"))),
                     ms(before), "%.2fx" % (before / c) if before and c else "-", r.get("same_voxels", "-"),
                     ms(f), faults(num(r.get("fresh_faults"))), ms(k4), faults(num(r.get("small_pages_faults"))),
                     "%.0f%%" % (100 * spread) if spread is not None else "-", "%.1f s" % pc if pc else "-", ratio(pc, c),
                     ratio(pc, before), ratio(pc, k4), size_text(m), size_text(pm) if pm else "-"])
    first = rows[0] if rows else {}
    md.append("The paper's figures (an Athlon at 1.4 GHz) stand next to ours; its \"3D array + bit array\" column against the dense "
              "store. Creation is one `build_tree` call (generate + validate + density classes + build, on 2 threads), best of 5 "
              "calls, with a `scratch_memory` kept across calls as an application creating many trees keeps it. \"recycled\": each "
              "call builds in the store the last one returned; \"fresh\": a new store each call, on huge pages where offered; "
              "\"4K pages\": fresh with `hypertree::huge_pages_wanted` off, so blocks of 1 MiB and more are mapped on 4 KiB pages as the dense array was before. Faults are minor page "
              "faults per call (`getrusage`). \"store build\" is the last step alone, into a fresh store / into the last one built "
              "(faults in brackets). \"before\": the recycled creation on the path before issue 27's rework "
              "(bench/support/creation_before.hpp), timed in alternating rounds with \"recycled\"; \"gain\" is before / recycled; "
              "\"same\": both paths' voxel lists equal. Each figure is the worst of %s runs of the whole sweep; spread is how far the runs' "
              "recycled times lie apart. Load average before the runs: %s; after: %s.\n"
              % (first.get("runs", "?"), first.get("load_before", "?"), first.get("load_after", "?")))
    md.append(table(["tree", "res", "store", "voxels", "store build: fresh / rebuilt", "creation (recycled)", "faults", "before", "gain", "same",
                     "fresh", "faults", "4K pages", "faults", "spread", "paper", "speedup", "before speedup", "4K pages speedup", "memory",
                     "paper memory"], body))


def render_section(path, images, md):
    md.append("## Hypertree rendering next to the paper's Table 1 (`bench_hypertree_render`)\n")
    if not path:
        md.append("_bench_hypertree_render.csv not found._\n")
        return
    rows = read_rows(path)
    tab = [r for r in rows if r.get("table") == "table"]
    if tab:
        # Per row of the table, both shadow methods (the CSV's setting: rays or sweep).
        merged = {}
        for r in tab:
            key = (r["tree"], r["resolution"], r["supersampling"], r["store"])
            entry = merged.setdefault(key, {"paper": num(r.get("paper_seconds"))})
            entry.setdefault(r.get("setting") or "rays", {})[r["marcher"]] = num(r.get("seconds"))
            if r.get("setting") == "sweep" and r.get("rmse"):
                entry["rmse"] = num(r.get("rmse"))
        body = []

        def ms(x):
            return "%.1f ms" % (1e3 * x) if x else "-"
        for (tree, res, s, store), v in merged.items():
            rays, sweep, paper = v.get("rays", {}), v.get("sweep", {}), v["paper"]
            best_rays = min([x for x in (rays.get("scalar"), rays.get("packet")) if x] or [None]) if rays else None
            best = min([x for x in (sweep.get("scalar"), sweep.get("packet")) if x] or [None]) if sweep else None
            setup = sweep.get("setup")
            body.append([tree, res, s, store, ms(rays.get("setup")), ms(rays.get("packet")), ms(setup), ms(sweep.get("scalar")),
                         ms(sweep.get("packet")), fmt(v.get("rmse")), "%.1f s" % paper if paper else "-",
                         "%.0fx" % (paper / best_rays) if paper and best_rays else "-", "%.0fx" % (paper / best) if paper and best else "-",
                         "%.0fx" % (paper / (best + setup)) if paper and best and setup else "-"])
        md.append("300 x 300 pixels, all cores; the paper's rendering times (index list, index list + bit array, 3D array + bit "
                  "array against our index_list, bit_array, dense). A frame is rendered by a marcher already made; `setup` makes "
                  "the marcher (its brick copy of the store and, with the light sweep, every voxel's swept shadow), once per tree and "
                  "lighting. Shadow rays (marched from every voxel in every frame) and the light sweep (the default) side by side, "
                  "their rounds alternating in one run; RMSE is the sweep's image against the shadow rays'. Speedups per frame "
                  "(shadow rays, sweep), and for one frame of the sweep with its setup.\n")
        md.append(table(["tree", "res", "supersampling", "store", "rays: setup", "rays: packet", "sweep: setup", "sweep: scalar",
                         "sweep: packet", "RMSE vs rays", "paper", "speedup (rays)", "speedup (sweep)", "sweep with setup"], body))
    err = [r for r in rows if r.get("table") == "error"]
    if err:
        md.append("\nSpeed against error (tree A, resolution 300; RMSE against a converged reference):\n")
        md.append(table(["setting", "time", "lookups", "RMSE"],
                        [[r.get("setting"), "%.1f ms" % (1e3 * num(r.get("seconds"), 0)), r.get("lookups"), r.get("rmse")] for r in err]))
        families = {}
        for r in err:
            family = re.sub(r"\s*[\d.]+$", "", r.get("setting", "")) or "setting"
            families.setdefault(family, []).append((num(r.get("rmse")), 1e3 * num(r.get("seconds"), 0)))
        if svg_chart(os.path.join(images, "hypertree_speed_error.svg"), "Hypertree marcher: time against RMSE (tree A)", "RMSE",
                     "ms per frame", sorted(families.items()), markers_only=False):
            md.append("\n![hypertree speed against error](images/hypertree_speed_error.svg)\n")


def openvdb_section(path, images, md):
    md.append("## Hypertree stores against OpenVDB (`bench_openvdb_peer`)\n")
    if not path:
        md.append("_bench_openvdb_peer.csv not found (configure with -DKRS_BENCH_OPENVDB=ON and run `bench/bench_openvdb_peer`)._\n")
        return
    rows = read_rows(path)
    if not rows:
        md.append("_bench_openvdb_peer.csv is empty._\n")
        return
    first = rows[0]
    md.append("Same voxels (trees A-D at resolution %s) in every store kind and in OpenVDB 10 grids (FloatGrid of density/255; a "
              "byte grid `Tree4<uint8_t,5,4,3>`). Random lookups on one thread; the render is one %s x %s view on %s threads, "
              "lighting off (on in the rows `lit_dense` and `openvdb_lit`, below), the same opacity law and sample positions on both sides (step factor %s; library shading %s). `+skipping` is what each "
              "marcher adds to skip empty space (the library marcher's brick copy of the store, which its rays read; the "
              "intersector's bool tree). RMSE and differing pixels are "
              "against the dense store's image.\n" % (first.get("resolution"), first.get("image_size"), first.get("image_size"),
                                                        first.get("threads"), first.get("step_factor"),
                                                        first.get("library_shading", "per-voxel")))
    body = []
    for r in rows:
        body.append([r["tree"], r["structure"], size_text(num(r.get("memory_bytes"))), size_text(num(r.get("skipping_bytes"))),
                     fmt(num(r.get("access_nonempty_ns"))), fmt(num(r.get("access_any_ns"))),
                     ("%.1f ms" % num(r["render_scalar_ms"])) if num(r.get("render_scalar_ms")) else "-",
                     ("%.1f ms" % num(r["render_packet_ms"])) if num(r.get("render_packet_ms")) else "-",
                     fmt(num(r.get("image_rmse"))), ("%.2f%%" % (100 * num(r["image_differing_share"])))
                     if num(r.get("image_differing_share")) is not None else "-"])
    md.append(table(["tree", "structure", "memory", "+skipping", "ns/lookup (non-empty)", "ns/lookup (any)", "render (scalar / OpenVDB)",
                     "render (packet)", "RMSE", "pixels differ"], body))
    # Ratios per tree.
    by_tree = {}
    for r in rows:
        by_tree.setdefault(r["tree"], {})[r["structure"]] = r
    summary = []
    for tree, s in by_tree.items():
        vdb, vdb8 = s.get("openvdb_float"), s.get("openvdb_uint8")
        if not vdb:
            continue
        best = min(num(s[k].get(c)) for k in ("dense", "index_list", "bit_array", "partitioned") if k in s
                   for c in ("render_scalar_ms", "render_packet_ms") if num(s[k].get(c)))
        vm, v8 = num(vdb["memory_bytes"]), num(vdb8["memory_bytes"]) if vdb8 else None

        def ratio(k, ref):
            return "%.2f" % (num(s[k]["memory_bytes"]) / ref) if k in s and ref else "-"
        summary.append([tree, ratio("index_list", vm), ratio("bit_array", vm), ratio("partitioned", vm), ratio("index_list", v8),
                        ratio("bit_array", v8), "%.1f ms" % best, "%.1f ms" % num(vdb["render_scalar_ms"]),
                        "%.2f" % (best / num(vdb["render_scalar_ms"]))])
    lit = []
    for tree, s_ in by_tree.items():
        ours, theirs = s_.get("lit_dense"), s_.get("openvdb_lit")
        if not ours or not theirs:
            continue
        frame = min(x for x in (num(ours.get("render_scalar_ms")), num(ours.get("render_packet_ms"))) if x)
        setup, vdb_frame, vdb_setup = num(ours.get("setup_ms"), 0), num(theirs["render_scalar_ms"]), num(theirs.get("setup_ms"), 0)
        lit.append([tree, "%.1f ms" % setup, "%.1f ms" % frame, "%.1f ms" % vdb_setup, "%.1f ms" % vdb_frame, "%.2f" % (frame / vdb_frame),
                    "%.2f" % ((frame + setup) / (vdb_frame + vdb_setup)), fmt(num(theirs.get("image_rmse")))])
    if lit:
        md.append("\nLighting on (`lit_dense`: library defaults, per-voxel shading with the light sweep; `openvdb_lit`: a shadow ray per "
                  "sample through a second intersector; ambient + diffuse x shadow, no normals; RMSE of OpenVDB's image against the "
                  "library's lit image shaded per sample, `lit_per_sample`, the same quantity but for the sweep):\n")
        md.append(table(["tree", "library setup", "library frame", "OpenVDB setup", "OpenVDB frame", "time ratio (frame)",
                         "time ratio (with setup)", "RMSE"], lit))
    md.append("\nRatios (store memory / grid memory; best library render time / OpenVDB render time, < 1 means the library is "
              "faster):\n")
    md.append(table(["tree", "index_list / FloatGrid", "bit_array / FloatGrid", "partitioned / FloatGrid", "index_list / byte grid",
                     "bit_array / byte grid", "best library render", "OpenVDB render", "time ratio"], summary))
    mem_series = {}
    for r in rows:
        mem_series.setdefault(r["structure"], []).append(("ABCD".find(r["tree"]) + 1, mib(num(r.get("memory_bytes")))))
    if svg_chart(os.path.join(images, "openvdb_memory.svg"), "Memory per structure (trees A-D = 1-4)", "tree", "MiB",
                 sorted(mem_series.items()), logy=True):
        md.append("\n![memory per structure](images/openvdb_memory.svg)\n")


HAND_WRITTEN = "<!-- hand-written below this line: kept by scripts/benchmark_report.py -->"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build", help="build directory holding the benchmark CSVs (or its bench/ folder)")
    ap.add_argument("--docs", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs"),
                    help="where benchmarks.md and images/ go (default: the repository's docs/)")
    args = ap.parse_args()
    docs = os.path.normpath(args.docs)
    images = os.path.join(docs, "images")
    m = machine()
    md = ["# Benchmarks\n",
          "Generated by `scripts/benchmark_report.py %s` on %s from the CSVs the benchmarks write; do not edit by hand, except the hand-written measurements at the end. "
          "How to reproduce:\n" % (os.path.basename(os.path.normpath(args.build)) or args.build, datetime.date.today().isoformat()),
          "```sh\n./scripts/install-deps.sh --peers   # Embree and OpenVDB, for the two peer benchmarks\n"
          "cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DKRS_BUILD_BENCHMARKS=ON -DKRS_BENCH_OPENVDB=ON -DKRS_BENCH_EMBREE=ON\n"
          "cmake --build build --target krs_benchmarks\n"
          "cd build && ./bench/bench_packet_trace && ./bench/bench_packet_trace_avx2 && ./bench/bench_hypertree_create && "
          "./bench/bench_hypertree_render && "
          "./bench/bench_openvdb_peer && ./bench/bench_embree_peer\n"
          "python3 ../scripts/benchmark_report.py .\n```\n",
          "## Machine\n",
          table(["CPU", "cores", "ISA", "OS", "compiler", "load average when reported (1, 5, 15 min)"],
                [[m["cpu"], m["cores"], m["isa"], m["os"], m["compiler"], m["load"]]]),
          "\nThe cores may be shared with other work: a load average above the core count means the timings below were taken "
          "on a busy machine and carry that noise.\n"]
    found = {name: find_csv(args.build, name) for name in ("bench_packet_trace.csv", "bench_packet_trace_avx2.csv",
                                                           "bench_hypertree_create.csv",
                                                           "bench_hypertree_render.csv", "bench_openvdb_peer.csv",
                                                           "bench_embree_peer.csv")}
    md.append("\nCSVs read: " + ", ".join("`%s`" % n if p else "~~%s~~ (absent)" % n for n, p in found.items()) + ".\n")
    krs, krs_memory = packet_trace_section(found["bench_packet_trace.csv"], images, md)
    packet_width_section(found["bench_packet_trace_avx2.csv"], md)
    embree_section(found["bench_embree_peer.csv"], krs, krs_memory, images, md)
    create_section(found["bench_hypertree_create.csv"], md)
    render_section(found["bench_hypertree_render.csv"], images, md)
    openvdb_section(found["bench_openvdb_peer.csv"], images, md)
    os.makedirs(docs, exist_ok=True)
    out = os.path.join(docs, "benchmarks.md")
    # Measurements run by hand (a comparison the CSVs do not hold) live after HAND_WRITTEN and are
    # kept as they are when the rest is regenerated.
    kept = ""
    if os.path.exists(out):
        with open(out) as f:
            old = f.read()
        if HAND_WRITTEN in old:
            kept = old[old.index(HAND_WRITTEN):]
    with open(out, "w") as f:
        f.write("\n".join(md))
        if kept:
            f.write("\n" + kept)
    print("wrote %s" % out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
