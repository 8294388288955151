#!/usr/bin/env python3
"""Writes the measured figures of docs/stability.md from the tests that measure them.

    scripts/stability_figures.py --tests BUILD/tests/krs_tests (--write | --check) [--doc DOC]

Runs the test cases of tests/test_stability.cpp in the given doctest executable (the portable
krs_tests), collects the lines they print as `figure <key> = <value>` (tests/support/figures.hpp),
and puts each value into the doc between `<!-- figure:<key> -->` and `<!-- /figure -->`.

--write  rewrites the doc in place.
--check  changes nothing; exits 1 when a value in the doc differs from what the tests print, or a
         key in the doc is printed by no test (the ctest stability_figures_in_docs). The figures
         depend on the compiler and its flags: when the build's `build.compiler` or `build.flags`
         differ from the doc's, the comparison is meaningless and the check exits 77, which ctest
         reports as skipped.

Keys the tests print but the doc does not quote are listed, never an error.
"""

import argparse
import re
import subprocess
import sys

FIGURE_LINE = re.compile(r"MESSAGE: figure (\S+) = (.*?)\s*$")
MARKER = re.compile(r"<!-- figure:(\S+) -->(.*?)<!-- /figure -->")
SKIP = 77


def measured_figures(tests):
    run = subprocess.run([tests, "--no-intro", "--no-version", "-sf=*test_stability.cpp"],
                         capture_output=True, text=True)
    figures = {}
    for line in run.stdout.splitlines():
        m = FIGURE_LINE.search(line)
        if m:
            figures[m.group(1)] = m.group(2)
    if run.returncode != 0:
        sys.stderr.write(run.stdout[-4000:] + run.stderr[-2000:])
        sys.exit(f"stability_figures: {tests} failed (exit {run.returncode}); its figures are not written")
    if not figures:
        sys.exit(f"stability_figures: {tests} printed no figures")
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tests", required=True, help="the portable doctest executable (krs_tests)")
    parser.add_argument("--doc", default="docs/stability.md")
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true")
    mode.add_argument("--check", action="store_true")
    args = parser.parse_args()

    figures = measured_figures(args.tests)
    with open(args.doc, encoding="utf-8") as f:
        doc = f.read()
    quoted = {m.group(1): m.group(2) for m in MARKER.finditer(doc)}

    unknown = sorted(k for k in quoted if k not in figures)
    if unknown:
        sys.exit("stability_figures: the doc quotes figures no test prints: " + ", ".join(unknown))
    for key in sorted(set(figures) - set(quoted)):
        print(f"not quoted in {args.doc}: {key} = {figures[key]}")

    if args.check:
        for key in ("build.compiler", "build.flags"):
            if quoted.get(key) != figures.get(key):
                print(f"{key}: the doc's figures come from {quoted.get(key)!r}, this build is "
                      f"{figures.get(key)!r}: nothing to compare")
                sys.exit(SKIP)
        stale = [(k, v, figures[k]) for k, v in quoted.items() if v != figures[k]]
        for key, doc_value, test_value in stale:
            print(f"{key}: doc {doc_value}, test {test_value}")
        if stale:
            print(f"{len(stale)} of {len(quoted)} figures in {args.doc} differ from what the tests print: "
                  f"run scripts/stability_figures.py --tests <build>/tests/krs_tests --write")
            sys.exit(1)
        print(f"{len(quoted)} figures in {args.doc} equal what the tests print")
        return

    updated = MARKER.sub(lambda m: f"<!-- figure:{m.group(1)} -->{figures[m.group(1)]}<!-- /figure -->", doc)
    if updated != doc:
        with open(args.doc, "w", encoding="utf-8") as f:
            f.write(updated)
        print(f"{args.doc}: figures rewritten")
    else:
        print(f"{args.doc}: already up to date")


if __name__ == "__main__":
    main()
