"""Flat-shaded triangle meshes of the parts (vertices, indices, normals) for pybullet's
``createVisualShape(GEOM_MESH, vertices=..., indices=..., normals=...)``: a hexagonal prism
(nut), a ring (washer) and a bolt lying on its side (head block + shaft block). Every face
has its own vertices so each carries its face normal (the renderer shades per vertex).
Lengths in metres; the mesh origin is the footprint's area centroid on the belt (z = 0)."""

import math

import numpy as np

from .parts import BOLT_HEAD, BOLT_SHAFT, PartClass


class Mesh:
    """Triangles accumulated face by face."""

    def __init__(self):
        self.vertices: list[tuple[float, float, float]] = []
        self.normals: list[tuple[float, float, float]] = []
        self.indices: list[int] = []

    def face(self, points, normal):
        """A planar convex polygon (fan-triangulated), points counter-clockwise seen from ``normal``."""
        start = len(self.vertices)
        for point in points:
            self.vertices.append(tuple(float(c) for c in point))
            self.normals.append(tuple(float(c) for c in normal))
        for i in range(1, len(points) - 1):
            self.indices += [start, start + i, start + i + 1]

    def prism(self, outline, z0, z1):
        """A vertical prism over a convex counter-clockwise outline (N x 2)."""
        outline = np.asarray(outline, float)
        self.face([(x, y, z1) for x, y in outline], (0, 0, 1))
        self.face([(x, y, z0) for x, y in outline[::-1]], (0, 0, -1))
        self._sides(outline, z0, z1, outward=True)

    def ring(self, r_out, r_in, z0, z1, segments=48):
        """A flat ring (washer): top annulus, outer and inner walls."""
        angles = np.linspace(0, 2 * math.pi, segments, endpoint=False)
        outer = np.c_[r_out * np.cos(angles), r_out * np.sin(angles)]
        inner = np.c_[r_in * np.cos(angles), r_in * np.sin(angles)]
        for i in range(segments):
            j = (i + 1) % segments
            quad = [outer[i], outer[j], inner[j], inner[i]]
            self.face([(x, y, z1) for x, y in quad], (0, 0, 1))
            self.face([(x, y, z0) for x, y in quad[::-1]], (0, 0, -1))
        self._sides(outer, z0, z1, outward=True)
        self._sides(inner, z0, z1, outward=False)

    def _sides(self, outline, z0, z1, outward):
        n = len(outline)
        for i in range(n):
            a, b = outline[i], outline[(i + 1) % n]
            edge = b - a
            normal = np.array([edge[1], -edge[0], 0.0]) / (np.linalg.norm(edge) or 1.0)
            quad = [(a[0], a[1], z0), (b[0], b[1], z0), (b[0], b[1], z1), (a[0], a[1], z1)]
            if not outward:
                normal, quad = -normal, quad[::-1]
            self.face(quad, normal)

    def arrays(self):
        return self.vertices, self.indices, self.normals


def hexagon(across_flats: float):
    """Counter-clockwise hexagon outline with a flat facing +y."""
    r = across_flats / math.sqrt(3)
    return [(r * math.cos(a), r * math.sin(a)) for a in np.arange(6) * math.pi / 3]


def rectangle(x0, x1, y0, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def bolt_axis_offset(part: PartClass) -> float:
    """x of the footprint centroid along the bolt axis, from the head's outer face."""
    head_len, head_w = BOLT_HEAD
    shaft_len = part.length - head_len
    head_area, shaft_area = head_len * head_w, shaft_len * BOLT_SHAFT[0]
    return (head_area * head_len / 2 + shaft_area * (head_len + shaft_len / 2)) / (head_area + shaft_area)


def part_mesh(part: PartClass) -> Mesh:
    """The mesh of one part class, origin at its footprint centroid, axis along +x."""
    mesh = Mesh()
    if part.kind == "nut":
        mesh.prism(hexagon(part.width), 0.0, part.height)
    elif part.kind == "washer":
        mesh.ring(part.width / 2, part.bore / 2, 0.0, part.height)
    else:
        head_len, head_w = BOLT_HEAD
        diameter, lift = BOLT_SHAFT
        x0 = -bolt_axis_offset(part)
        mesh.prism(rectangle(x0, x0 + head_len, -head_w / 2, head_w / 2), 0.0, part.height)
        mesh.prism(rectangle(x0 + head_len, x0 + part.length, -diameter / 2, diameter / 2), lift, lift + diameter)
    return mesh
