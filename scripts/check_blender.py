# Run by scripts/check_blender.sh inside Blender (blender -b --factory-startup --python THIS -- ARGS):
# imports each export kind with Blender's own importers, default options apart from the glTF
# numpy workaround, and compares what Blender made with what the programs printed. Prints one
# "check_blender: ok|FAIL ..." line per check and exits 1 on any failure.
#   ARGS: key=value pairs, see check_blender.sh.
import json
import math
import re
import sys

import bpy
import mathutils

args = dict(a.split("=", 1) for a in sys.argv[sys.argv.index("--") + 1:])
failures = []


def check(what, ok, detail):
    print(f"check_blender: {'ok' if ok else 'FAIL'} {what}: {detail}", flush=True)
    if not ok:
        failures.append(what)


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def meshes():
    return [o for o in bpy.context.scene.objects if o.type == "MESH"]


def import_gltf(path):
    # Debian's Blender 3.4 glTF importer fails with its default shading option on numpy >= 1.24
    # ("module 'numpy' has no attribute 'bool'", glTF-Blender-IO #1844, fixed in Blender 3.5).
    bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")


def world_box(objects):
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    for o in objects:
        for corner in o.bound_box:
            p = o.matrix_world @ mathutils.Vector(corner)
            for a in range(3):
                lo[a], hi[a] = min(lo[a], p[a]), max(hi[a], p[a])
    return [hi[a] - lo[a] for a in range(3)]


def colours_by_position(obj):
    # Each vertex's linear colour (Blender's own decoding of the file's encoding), keyed by its
    # world position rounded to 1e-4, the same vertex in every file.
    mesh = obj.data
    attribute = mesh.color_attributes[0]
    out = {}
    if attribute.domain == "POINT":
        for v, c in zip(mesh.vertices, attribute.data):
            p = obj.matrix_world @ v.co
            out[tuple(round(x, 4) for x in p)] = tuple(c.color[:3])
    else:  # per face corner
        for loop, c in zip(mesh.loops, attribute.data):
            p = obj.matrix_world @ mesh.vertices[loop.vertex_index].co
            out[tuple(round(x, 4) for x in p)] = tuple(c.color[:3])
    return out


def srgb(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


colours = {}
# GLB, PLY and OBJ of one mesh: one object each with the printed vertex and face counts.
for kind in ("glb", "ply", "obj"):
    path = args[kind]
    reset()
    if kind == "glb":
        import_gltf(path)
    elif kind == "ply":
        bpy.ops.import_mesh.ply(filepath=path)
    else:
        bpy.ops.wm.obj_import(filepath=path)  # Blender 3.4's C++ importer (it reads colours); OBJ is y-up, it converts
    objs = meshes()
    check(f"{kind}: objects", len(objs) == 1, f"{len(objs)} mesh objects (want 1)")
    if len(objs) != 1:
        continue
    m = objs[0].data
    # The OBJ and glTF importers keep the file's vertices; the PLY's keeps them too.
    check(f"{kind}: vertices", len(m.vertices) == int(args["vertices"]), f"{len(m.vertices)} (krs_export printed {args['vertices']})")
    check(f"{kind}: faces", len(m.polygons) == int(args["triangles"]), f"{len(m.polygons)} (krs_export printed {args['triangles']})")
    # Upright: the ground (a plane meshed within the scene's box, the one open sheet: every closed
    # surface's area-weighted normals sum to zero) faces up, so the sum points along +z.
    up = mathutils.Vector()
    for f in m.polygons:
        up += (objs[0].matrix_world.to_3x3() @ f.normal) * f.area
    up.normalize()
    # (The box is reported, not checked: the ground, meshed over the scene's box, is wider than the
    # tree is tall: 7.29 x 7.29 x 6.65 at resolution 48.)
    check(f"{kind}: stands upright", up.z > 0.99, f"area-weighted normal sum {tuple(round(x, 3) for x in up)}: along +z; "
          f"world box extent {[round(e, 3) for e in world_box(objs)]} (x, y, z)")
    check(f"{kind}: colours", len(m.color_attributes) > 0, f"{len(m.color_attributes)} colour attributes")
    if len(m.color_attributes) > 0:
        colours[kind] = colours_by_position(objs[0])

# The same vertex's colour from the three files, in sRGB (a byte's step is 1/255 there).
if len(colours) == 3:
    common = set(colours["glb"]) & set(colours["ply"]) & set(colours["obj"])
    worst = 0.0
    for key in common:
        for a, b in (("glb", "ply"), ("glb", "obj"), ("ply", "obj")):
            for ca, cb in zip(colours[a][key], colours[b][key]):
                worst = max(worst, abs(srgb(ca) - srgb(cb)))
    check("colours agree", len(common) > 0.9 * int(args["vertices"]) and worst <= 1 / 255,
          f"{len(common)} vertices in all three files; largest sRGB difference {worst * 255:.3f} / 255 (at most 1)")

# Instanced glTF: one placed object per printed instance, each at the transform krs::expand gives.
# An object showing kernel K carries K's points (its box centre and that moved by one along x, y
# and z: they pin a rigid motion), which must land within 1e-4 of where one of K's expansion
# instances puts them; an object showing "levels below L" (the mirror levels under the instanced
# ones, meshed whole) carries the origin and unit points of its own space, which must land where
# an isometry of level L (the instances of a kernel of level L) puts them. Each expansion instance
# is used once, and every instance of each part Blender shows is there.
reset()
import_gltf(args["instances"])
objs = meshes()
check("instances: placed", len(objs) == int(args["instance_count"]), f"{len(objs)} mesh objects (krs_export printed {args['instance_count']})")
with open(args["expansion"]) as f:
    expansion = json.load(f)


def blender_frame(p):
    # Blender's glTF importer turns glTF's y-up (the scene's frame) z-up: (x, y, z) -> (x, -z, y).
    return mathutils.Vector((p[0], -p[2], p[1]))


def isometry(instance, p):
    r, t = instance["rotation"], instance["translation"]
    return [sum(r[3 * row + c] * p[c] for c in range(3)) + t[row] for row in range(3)]


unit_points = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
kernels = expansion["kernels"]
first_of_level = {}
for k, kernel in enumerate(kernels):
    first_of_level.setdefault(kernel["level"], k)
expected = {}  # part name -> the world points of each of its expansion instances, Blender's frame
placed = {}  # part name -> the world points of each object showing it
unnamed = []
for o in objs:
    # The glTF mesh's name, "kernel K" or "levels below L", then " (mirrored)" for the part mirrored
    # through x = 0 in its own space (krs/mesh/instances.hpp): its points are mirrored too.
    match = re.fullmatch(r"(kernel|levels below) (\d+)( \(mirrored\))?(\.\d+)?", o.data.name)
    if not match or (match.group(1) == "levels below" and int(match.group(2)) not in first_of_level):
        unnamed.append(o.data.name)
        continue
    part = f"{match.group(1)} {match.group(2)}"
    if part not in expected:
        kernel = int(match.group(2)) if match.group(1) == "kernel" else first_of_level[int(match.group(2))]
        local = kernels[kernel]["points"] if match.group(1) == "kernel" else unit_points
        expected[part] = [(local, [blender_frame(isometry(i, p)) for p in local]) for i in expansion["instances"] if i["kernel"] == kernel]
    local = expected[part][0][0] if expected[part] else unit_points
    if match.group(3):
        local = [(-p[0], p[1], p[2]) for p in local]
    placed.setdefault(part, []).append([o.matrix_world @ blender_frame(p) for p in local])
check("instances: meshes named by their part", not unnamed, f"{len(unnamed)} objects whose mesh names no kernel or level {unnamed[:3]}")
worst = 0.0
unmatched = 0
for part, objects in placed.items():
    candidates = [points for _, points in expected[part]]
    unmatched += abs(len(objects) - len(candidates))
    for points in objects:
        if not candidates:
            break
        distance = [max((a - b).length for a, b in zip(points, c)) for c in candidates]
        best = min(range(len(candidates)), key=distance.__getitem__)
        worst = max(worst, distance[best])
        candidates.pop(best)
shown = sum(len(expected[part]) for part in placed)
check("instances: where krs::expand puts them", unmatched == 0 and worst <= 1e-4 and shown == len(objs),
      f"{len(objs)} objects of {len(placed)} parts ({', '.join(sorted(placed))}), {shown} expansion placements of those parts, "
      f"{unmatched} unmatched; largest distance of a part's point from the expansion's {worst:.2e} (at most 1e-4)")

# VDB: a volume with the density, level and part grids, upright.
reset()
bpy.ops.object.volume_import(filepath=args["vdb"])
volumes = [o for o in bpy.context.scene.objects if o.type == "VOLUME"]
check("vdb: objects", len(volumes) == 1, f"{len(volumes)} volume objects (want 1)")
if volumes:
    grids = volumes[0].data.grids
    grids.load()
    names = sorted(g.name for g in grids)
    check("vdb: grids", names == ["density", "level", "part"], f"{names}")
    # Written --up z: the tree (taller than wide) stands, its world box longest along Blender's z.
    extent = world_box(volumes)
    check("vdb: stands upright", extent[2] > max(extent[0], extent[1]),
          f"world box extent {[round(e, 3) for e in extent]} (x, y, z): longest along z")
    # One small frame in Cycles: the volume renders (a few samples, a tiny image: seconds).
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False  # Debian builds Blender without OpenImageDenoise
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.render.film_transparent = True  # alpha is then the volume's coverage
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    centre = sum((volumes[0].matrix_world @ mathutils.Vector(c) for c in volumes[0].bound_box), mathutils.Vector()) / 8
    cam.location = centre + mathutils.Vector((0, -3 * max(extent), 0))
    cam.rotation_euler = (math.pi / 2, 0, 0)
    light = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    scene.collection.objects.link(light)
    mat = bpy.data.materials.new("fog")
    mat.use_nodes = True
    volumes[0].data.materials.append(mat)
    scene.render.filepath = args["render"]
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(args["render"])
    pixels = list(image.pixels)
    lit = sum(1 for i in range(0, len(pixels), 4) if pixels[i + 3] > 0.01)
    check("vdb: Cycles frame", 0 < lit < len(pixels) // 4, f"{lit} of {len(pixels) // 4} pixels covered by the volume")

print(f"check_blender: {len(failures)} failed" + (f": {', '.join(failures)}" if failures else ""), flush=True)
sys.exit(1 if failures else 0)
