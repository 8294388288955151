#!/usr/bin/env python3
"""Checks the include graph of include/ against the layer table of docs/design.md.

    scripts/check_layers.py [--root ROOT]

docs/design.md#layers holds the one statement of the layering, as two Markdown tables that this
script reads (there is no second copy here):

- the layer table, columns `layer | headers | ... | may include`: rows from the bottom layer up,
  each naming its headers (a folder such as `krs/core/`, or single headers) and what they may
  include besides their own layer (layer names, or single headers in backticks);
- the umbrella table, columns `umbrella | gives every header of | but`: a header that must reach,
  directly or through the headers it includes, every header of the folders named, except those
  named in the last column.

A header's layer is the row that names the header itself, else the row that names its nearest
folder. The script fails (exit 1), printing `file:line: message` for each problem, on:
- an #include (quoted, or in angle brackets naming a header of include/) that its layer's row
  does not allow, naming both layers;
- a quoted #include of a file that is not under include/;
- a header under include/ in no row;
- a table that cannot be trusted: a row naming a missing header or folder, a header in two rows,
  a layer named twice, or a `may include` naming an unknown layer or one of a later row
  (the layers must go one way), and an umbrella that does not reach every header it must.
It prints the number of headers and includes checked when everything holds (ctest include_layers).
"""

import argparse
import pathlib
import re
import sys

DOC = "docs/design.md"
ANCHOR = '<a id="layers"></a>'
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
CODE = re.compile(r"`([^`]+)`")


class Problems:
    def __init__(self):
        self.lines = []

    def add(self, where, message):
        self.lines.append(f"{where}: {message}")


def cells(line):
    """The cells of a Markdown table row, stripped; None for a line that is not a row."""
    line = line.strip()
    if not (line.startswith("|") and line.endswith("|")):
        return None
    return [c.strip() for c in line[1:-1].split("|")]


def tables_after_anchor(doc_lines):
    """Every table of the layers section: (header cells, [(line number, cells)...])."""
    try:
        start = next(i for i, l in enumerate(doc_lines) if l.strip() == ANCHOR)
    except StopIteration:
        sys.exit(f"check_layers: {DOC} has no {ANCHOR}")
    tables, current = [], None
    for number in range(start + 1, len(doc_lines)):
        line = doc_lines[number]
        if number > start + 1 and line.startswith("## "):
            break
        row = cells(line)
        if row is None:
            current = None
            continue
        if current is None:
            current = (row, [])
            tables.append(current)
        elif not all(re.fullmatch(r":?-+:?", c) for c in row):
            current[1].append((number + 1, row))
    return tables


def find_table(tables, first, last):
    for header, rows in tables:
        if header and header[0] == first and header[-1] == last:
            return rows
    sys.exit(f"check_layers: {DOC}#layers has no table with columns `{first} | ... | {last}`")


def header_files(include):
    return sorted(p.relative_to(include).as_posix() for p in include.rglob("*") if p.suffix in (".hpp", ".h"))


def read_layers(rows, headers, problems):
    """Layers in table order: name -> (rank, allowed layer names, allowed single headers)."""
    layers, owner = {}, {}
    folders = {h.rsplit("/", 1)[0] + "/" for h in headers}
    folders |= {f[: i + 1] for f in folders for i in range(len(f)) if f[i] == "/"}
    for number, row in rows:
        where = f"{DOC}:{number}"
        name, named, allowed = row[0], CODE.findall(row[1]), row[-1]
        if name in layers:
            problems.add(where, f"layer {name} has two rows")
            continue
        layer_names, single = set(), set()
        for token in filter(None, (t.strip().strip("`") for t in allowed.split(","))):
            if "/" in token:
                if token not in headers:
                    problems.add(where, f"layer {name} may include {token}, which is no header of include/")
                elif layer_of(token, owner) is None:
                    problems.add(where, f"layer {name} may include {token}, which is in no earlier row")
                single.add(token)
            elif token not in layers:
                problems.add(where, f"layer {name} may include layer {token}, which is no earlier row "
                                    "(rows go from the bottom up; a layer names only layers below it)")
            else:
                layer_names.add(token)
        for entry in named:
            if entry in owner:
                problems.add(where, f"{entry} is in two rows: {owner[entry]} and {name}")
            elif entry not in headers and entry not in folders:
                problems.add(where, f"layer {name} names {entry}, which is no header or folder of include/")
            owner[entry] = name
        layers[name] = (len(layers), layer_names, single)
    return layers, owner


def layer_of(header, owner):
    if header in owner:
        return owner[header]
    folder = header
    while "/" in folder:
        folder = folder.rsplit("/", 1)[0]
        if folder + "/" in owner:
            return owner[folder + "/"]
    return None


def check_includes(include, headers, layers, owner, problems):
    graph, count = {}, 0
    for header in headers:
        layer = layer_of(header, owner)
        if layer is None:
            problems.add(f"include/{header}", "its folder is in no row of the layer table "
                                              f"({DOC}#layers): add it to a layer")
        graph[header] = set()
        text = (include / header).read_text(encoding="utf-8").splitlines()
        for number, line in enumerate(text, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            quoted, target = m.group(1) == '"', m.group(2)
            where = f"include/{header}:{number}"
            if target not in headers:
                if quoted:
                    problems.add(where, f"includes \"{target}\", which is no header of include/ "
                                        "(headers name each other from include/)")
                continue
            count += 1
            graph[header].add(target)
            target_layer = layer_of(target, owner)
            if layer is None or target_layer is None or target_layer == layer:
                continue
            _, allowed_layers, allowed_headers = layers[layer]
            if target_layer not in allowed_layers and target not in allowed_headers:
                direction = ("a layer above it" if layers[target_layer][0] > layers[layer][0]
                             else "a layer below it that its row does not list")
                problems.add(where, f"includes {target}: layer {layer} may not include layer {target_layer} "
                                    f"({direction}; {DOC}#layers)")
    return graph, count


def check_umbrellas(rows, headers, graph, problems):
    for number, row in rows:
        where = f"{DOC}:{number}"
        umbrella = CODE.findall(row[0])
        # Paths only: the last column also names targets (`krs::mesh_gltf`) in code.
        covered, excepted = ([c for c in CODE.findall(cell) if "/" in c] for cell in (row[1], row[-1]))
        if len(umbrella) != 1 or umbrella[0] not in headers:
            problems.add(where, f"the umbrella {row[0]} is not one header of include/")
            continue
        umbrella = umbrella[0]
        for entry in covered + excepted:
            if entry not in headers and not any(h.startswith(entry) for h in headers if entry.endswith("/")):
                problems.add(where, f"{entry} is no header or folder of include/")
        reached, todo = {umbrella}, [umbrella]
        while todo:
            for target in graph.get(todo.pop(), ()):
                if target not in reached:
                    reached.add(target)
                    todo.append(target)
        def named(header, entries):
            return any(header == e or (e.endswith("/") and header.startswith(e)) for e in entries)
        for header in headers:
            if header != umbrella and named(header, covered) and not named(header, excepted) and header not in reached:
                problems.add(f"include/{umbrella}", f"does not reach {header} (the umbrella table, {where}, "
                                                    "says it gives every header of "
                                                    f"{', '.join(covered)}): include it")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent, type=pathlib.Path)
    root = parser.parse_args().root
    include = root / "include"
    doc_lines = (root / DOC).read_text(encoding="utf-8").splitlines()
    tables = tables_after_anchor(doc_lines)
    headers = header_files(include)
    problems = Problems()
    layers, owner = read_layers(find_table(tables, "layer", "may include"), set(headers), problems)
    graph, count = check_includes(include, headers, layers, owner, problems)
    check_umbrellas(find_table(tables, "umbrella", "but"), set(headers), graph, problems)
    if problems.lines:
        print("\n".join(problems.lines))
        print(f"check_layers: {len(problems.lines)} problem(s) with the layers of {DOC}#layers")
        return 1
    print(f"check_layers: {len(headers)} headers in {len(layers)} layers, {count} includes within include/, all allowed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
