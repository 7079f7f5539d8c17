#!/usr/bin/env python3
"""Writes the small OBJ assets of scenes/meshes/ (run once; the output is checked in).

- cube.obj:       closed cube, side 1 m, centred at the origin, 6 quads wound outward.
- icosphere.obj:  closed icosphere of radius 1 m (icosahedron subdivided twice: 162 vertices,
                  320 triangles), wound outward.
- blob.obj:       a closed bunny-like blob about 1 m long (x), 0.95 m high (y): an icosphere
                  (3 subdivisions: 642 vertices, 1280 triangles) pushed out radially into an
                  ellipsoidal body, a head at the front (+x, up) and two ears on it, wound outward.
- cloth_disc.obj: a disc of radius 0.5 m in the xz plane at y = 0 with an irregular
                  triangulation (8 jittered rings, 217 vertices, 384 triangles), normals +y,
                  with texture coordinates u = x + 0.5, v = z + 0.5.

Deterministic (fixed random seed). Usage: python3 scripts/make_meshes.py [out_dir]
"""
import math
import os
import random
import sys


def write_obj(path, header, vertices, faces, texcoords=None):
    with open(path, "w") as f:
        f.write(f"# {header}\n# {len(vertices)} vertices, {len(faces)} faces; "
                "written by scripts/make_meshes.py\n")
        for v in vertices:
            f.write("v {:.9g} {:.9g} {:.9g}\n".format(*v))
        if texcoords:
            for t in texcoords:
                f.write("vt {:.9g} {:.9g}\n".format(*t))
        for face in faces:
            if texcoords:
                f.write("f " + " ".join(f"{i + 1}/{i + 1}" for i in face) + "\n")
            else:
                f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def check_closed(faces):
    edges = {}
    for f in faces:
        for k in range(len(f)):
            a, b = f[k], f[(k + 1) % len(f)]
            edges[(a, b)] = edges.get((a, b), 0) + 1
    for (a, b), n in edges.items():
        assert n == 1 and edges.get((b, a)) == 1, "not closed and consistently wound"


def cube():
    v = [[x, y, z] for z in (-0.5, 0.5) for y in (-0.5, 0.5) for x in (-0.5, 0.5)]
    # index = x + 2 y + 4 z (x, y, z in {0, 1}); counter-clockwise seen from outside
    faces = [[0, 2, 3, 1], [4, 5, 7, 6],  # -z, +z
             [0, 1, 5, 4], [2, 6, 7, 3],  # -y, +y
             [0, 4, 6, 2], [1, 3, 7, 5]]  # -x, +x
    for f in faces:
        n = cross(sub(v[f[1]], v[f[0]]), sub(v[f[2]], v[f[0]]))
        c = [sum(v[i][k] for i in f) / 4 for k in range(3)]
        assert dot(n, c) > 0
    check_closed(faces)
    return v, faces


def icosphere(levels):
    t = (1 + math.sqrt(5)) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    v = [[c / math.sqrt(dot(p, p)) for c in p] for p in v]
    faces = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
             [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
             [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    for _ in range(levels):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(v[a][k] + v[b][k]) / 2 for k in range(3)]
                r = math.sqrt(dot(p, p))
                v.append([c / r for c in p])
                mid[key] = len(v) - 1
            return mid[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = new
    for f in faces:
        n = cross(sub(v[f[1]], v[f[0]]), sub(v[f[2]], v[f[0]]))
        assert dot(n, v[f[0]]) > 0
    check_closed(faces)
    return v, faces


def blob():
    v, faces = icosphere(3)

    def bump(p, centre, width):
        c = [x / math.sqrt(dot(centre, centre)) for x in centre]
        d = sub(p, c)
        return math.exp(-dot(d, d) / (width * width))

    out = []
    for p in v:
        r = (1.0 + 0.45 * bump(p, [0.7, 0.55, 0.0], 0.45)          # head
             + 0.55 * bump(p, [0.25, 1.0, 0.18], 0.16)              # ears
             + 0.55 * bump(p, [0.25, 1.0, -0.18], 0.16))
        out.append([0.5 * r * p[0], 0.36 * r * p[1], 0.38 * r * p[2]])
    # Radial pushes keep the sphere's topology and winding: still closed, normals outward.
    check_closed(faces)
    return out, faces


def cloth_disc(rings=8, radius=0.5, seed=7):
    rng = random.Random(seed)
    # ring k has 6 k points (k >= 1) at angles offset by a random turn, jittered; interior rings
    # are also jittered radially. Each ring is a list of (turn in [0, 1), vertex index).
    vertices = [[0.0, 0.0, 0.0]]
    ring_points = [[(0.0, 0)]]
    for k in range(1, rings + 1):
        n = 6 * k
        offset = rng.random()
        pts = []
        for i in range(n):
            turn = (offset + (i + 0.35 * (rng.random() - 0.5)) / n) % 1.0
            r = radius * k / rings
            if k < rings:
                r += radius / rings * 0.3 * (rng.random() - 0.5)
            a = 2 * math.pi * turn
            vertices.append([r * math.cos(a), 0.0, r * math.sin(a)])
            pts.append((turn, len(vertices) - 1))
        pts.sort()
        ring_points.append(pts)
    faces = []
    for k in range(1, rings + 1):
        inner, outer = ring_points[k - 1], ring_points[k]
        m, n = len(inner), len(outer)
        if m == 1:  # the centre: a fan
            faces += [[inner[0][1], outer[j][1], outer[(j + 1) % n][1]] for j in range(n)]
            continue
        # Unwrapped turns: the inner ring from its first point, the outer ring from its last
        # point at or before that turn; then zip the two rings by increasing turn.
        u = [inner[i % m][0] + (i // m) for i in range(m + 1)]
        j0 = max([j for j in range(n) if outer[j][0] <= u[0]], default=n - 1)
        v = []
        for j in range(n + 1):
            t = outer[(j0 + j) % n][0]
            while v and t < v[-1]:
                t += 1.0
            if not v and t > u[0]:
                t -= 1.0
            v.append(t)
        I = [inner[i % m][1] for i in range(m + 1)]
        O = [outer[(j0 + j) % n][1] for j in range(n + 1)]
        i = j = 0
        while i < m or j < n:
            if j < n and (i == m or v[j + 1] <= u[i + 1]):
                faces.append([I[i], O[j], O[j + 1]])
                j += 1
            else:
                faces.append([I[i], O[j], I[i + 1]])
                i += 1
    # Every triangle has the same winding (none folded); turn them so that the normal is +y.
    signs = set()
    for f in faces:
        n = cross(sub(vertices[f[1]], vertices[f[0]]), sub(vertices[f[2]], vertices[f[0]]))
        assert abs(n[1]) > 1e-6
        signs.add(n[1] > 0)
    assert len(signs) == 1
    if signs == {False}:
        for f in faces:
            f[1], f[2] = f[2], f[1]
    # A disc: every edge in one or two triangles, V - E + F = 1.
    edges = {}
    for f in faces:
        for e in range(3):
            key = tuple(sorted((f[e], f[(e + 1) % 3])))
            edges[key] = edges.get(key, 0) + 1
    assert max(edges.values()) <= 2
    assert len(vertices) - len(edges) + len(faces) == 1
    texcoords = [[p[0] + 0.5, p[2] + 0.5] for p in vertices]
    return vertices, faces, texcoords


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "meshes")
    os.makedirs(out, exist_ok=True)
    v, f = cube()
    write_obj(os.path.join(out, "cube.obj"), "closed cube, side 1 m, centred at the origin", v, f)
    v, f = icosphere(2)
    write_obj(os.path.join(out, "icosphere.obj"), "closed icosphere, radius 1 m, 2 subdivisions", v, f)
    v, f = blob()
    write_obj(os.path.join(out, "blob.obj"), "closed bunny-like blob, about 1 m long, head at +x", v, f)
    v, f, t = cloth_disc()
    write_obj(os.path.join(out, "cloth_disc.obj"),
              "cloth disc, radius 0.5 m, xz plane at y = 0, normals +y", v, f, t)


if __name__ == "__main__":
    main()
