#!/usr/bin/python3
"""make-cornell-scene.py — writes the Cornell box idmr ships (data/cornell/).

The scene is the project's own: five diffuse walls and an area light built from Mitsuba's
`rectangle` shape, a low-poly block (`cube`), and a finely tessellated (2,3) torus knot tube
written as a binary PLY (the "high-tessellated object" the reduction works on). Mitsuba 3
dialect. Run it again to regenerate; the output is deterministic.

    scripts/make-cornell-scene.py [--segments 600] [--sides 80] [OUTDIR]
"""
import argparse
import os
import struct

import numpy as np


def torus_knot_tube(p, q, segments, sides, knot_radius, tube_radius):
    """Vertices (n, 3) and triangles (m, 3) of a closed tube around a (p, q) torus knot."""
    t = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)

    def curve(s):
        r = knot_radius * (2.0 + np.cos(q * s)) / 3.0
        return np.stack([r * np.cos(p * s), r * np.sin(p * s), -knot_radius * np.sin(q * s) / 3.0], axis=-1)

    c = curve(t)
    tangent = curve(t + 1e-4) - curve(t - 1e-4)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # A frame that turns smoothly along the curve: normal from the curvature direction.
    second = curve(t + 1e-3) + curve(t - 1e-3) - 2.0 * c
    normal = second - (second * tangent).sum(axis=1, keepdims=True) * tangent
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangent, normal)
    a = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    ring = np.cos(a)[None, :, None] * normal[:, None, :] + np.sin(a)[None, :, None] * binormal[:, None, :]
    vertices = (c[:, None, :] + tube_radius * ring).reshape(-1, 3)

    i = np.arange(segments)[:, None]
    j = np.arange(sides)[None, :]
    v00 = i * sides + j
    v10 = ((i + 1) % segments) * sides + j
    v01 = i * sides + (j + 1) % sides
    v11 = ((i + 1) % segments) * sides + (j + 1) % sides
    # Winding chosen so that the geometric normal points out of the tube.
    first = np.stack([v00, v10, v11], axis=-1).reshape(-1, 3)
    second_tri = np.stack([v00, v11, v01], axis=-1).reshape(-1, 3)
    triangles = np.concatenate([first, second_tri])
    # Check the orientation on one triangle and flip all if it points inwards.
    v = vertices[triangles[0]]
    n = np.cross(v[1] - v[0], v[2] - v[0])
    if np.dot(n, v[0] - c[0]) < 0:
        triangles = triangles[:, ::-1]
    return vertices.astype(np.float32), triangles.astype(np.int32)


def write_binary_ply(path, vertices, triangles):
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        "comment idmr Cornell box: (2,3) torus knot tube, written by scripts/make-cornell-scene.py\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = triangles
    temporary = path + ".tmp"
    with open(temporary, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vertices.astype("<f4").tobytes())
        f.write(faces.tobytes())
    os.replace(temporary, path)


def rectangle(name, steps, bsdf):
    """A wall: Mitsuba's rectangle moved by the transform `steps` (one element each)."""
    transform = "".join("            %s\n" % step for step in steps)
    return ('    <shape type="rectangle" id="%s">\n        <transform name="to_world">\n%s'
            '        </transform>\n        <ref id="%s"/>\n    </shape>\n' % (name, transform, bsdf))


WALLS = "".join(rectangle(*wall) for wall in (
    ("floor", ('<rotate x="1" angle="-90"/>', '<translate y="-1"/>'), "white"),
    ("ceiling", ('<rotate x="1" angle="90"/>', '<translate y="1"/>'), "white"),
    ("back", ('<translate z="-1"/>',), "white"),
    ("red_wall", ('<rotate y="1" angle="90"/>', '<translate x="-1"/>'), "red"),
    ("green_wall", ('<rotate y="1" angle="-90"/>', '<translate x="1"/>'), "green"),
))

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<!-- idmr's Cornell box (written by scripts/make-cornell-scene.py; the project's own geometry).
     Box [-1,1]^3, camera on +z. Mitsuba 3 dialect. -->
<scene version="3.0.0">
    <default name="res" value="256"/>

    <sensor type="perspective">
        <float name="fov" value="39.3077"/>
        <string name="fov_axis" value="smaller"/>
        <transform name="to_world">
            <lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
        </film>
    </sensor>

    <bsdf type="diffuse" id="white">
        <rgb name="reflectance" value="0.725, 0.71, 0.68"/>
    </bsdf>
    <bsdf type="diffuse" id="red">
        <rgb name="reflectance" value="0.63, 0.065, 0.05"/>
    </bsdf>
    <bsdf type="diffuse" id="green">
        <rgb name="reflectance" value="0.14, 0.45, 0.091"/>
    </bsdf>
    <bsdf type="diffuse" id="orange">
        <rgb name="reflectance" value="0.8, 0.6, 0.3"/>
    </bsdf>

%(walls)s    <shape type="rectangle" id="light">
        <transform name="to_world">
            <scale x="0.25" y="0.25"/>
            <rotate x="1" angle="90"/>
            <translate y="0.99"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0, 0, 0"/>
        </bsdf>
        <emitter type="area">
            <rgb name="radiance" value="17, 12, 4"/>
        </emitter>
    </shape>

    <shape type="cube" id="block">
        <transform name="to_world">
            <scale x="0.28" y="0.55" z="0.28"/>
            <rotate y="1" angle="-18"/>
            <translate x="-0.42" y="-0.45" z="-0.35"/>
        </transform>
        <ref id="white"/>
    </shape>
    <shape type="ply" id="knot">
        <string name="filename" value="meshes/knot.ply"/>
        <transform name="to_world">
            <rotate x="1" angle="-70"/>
            <translate x="0.35" y="-0.5" z="0.25"/>
        </transform>
        <ref id="orange"/>
    </shape>
</scene>
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", nargs="?", default=os.path.join(os.path.dirname(__file__), "..", "data", "cornell"))
    parser.add_argument("--segments", type=int, default=600)
    parser.add_argument("--sides", type=int, default=80)
    args = parser.parse_args()
    os.makedirs(os.path.join(args.outdir, "meshes"), exist_ok=True)
    vertices, triangles = torus_knot_tube(2, 3, args.segments, args.sides, knot_radius=0.42, tube_radius=0.085)
    write_binary_ply(os.path.join(args.outdir, "meshes", "knot.ply"), vertices, triangles)
    scene_path = os.path.join(args.outdir, "scene.xml")
    with open(scene_path + ".tmp", "w") as f:
        f.write(SCENE % {"walls": WALLS})
    os.replace(scene_path + ".tmp", scene_path)
    print(f"wrote {scene_path}: knot {len(vertices)} vertices, {len(triangles)} triangles")


if __name__ == "__main__":
    main()
