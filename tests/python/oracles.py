"""Independent answers the tests compare bvhlab with."""

import math

import numpy as np


def brute_force(tris, spheres, origins, dirs):
    """Closest hit over every primitive, float64, vectorised Möller–Trumbore and sphere roots."""
    o = origins.astype(np.float64)[:, None, :]
    d = dirs.astype(np.float64)[:, None, :]
    best_t = np.full(len(origins), np.inf)
    best_id = np.full(len(origins), -1)
    best_kind = np.zeros(len(origins), int)
    if len(tris):
        v0, v1, v2 = (tris[:, k].astype(np.float64)[None] for k in range(3))
        e1, e2 = v1 - v0, v2 - v0
        p = np.cross(d, e2)
        det = np.einsum("rtk,rtk->rt", e1.repeat(len(o), 0), p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = o - v0
            u = np.einsum("rtk,rtk->rt", tv, p) * inv
            q = np.cross(tv, e1)
            v = np.einsum("rtk,rtk->rt", d.repeat(e1.shape[1], 1), q) * inv
            t = np.einsum("rtk,rtk->rt", e2.repeat(len(o), 0), q) * inv
            ok = (det != 0) & (u >= 0) & (u <= 1) & (v >= 0) & (u + v <= 1) & (t > 0)  # NaN: not ok
        t = np.where(ok, t, np.inf)
        best_id = t.argmin(1)
        best_t = t[np.arange(len(o)), best_id]
        best_id = np.where(np.isfinite(best_t), best_id, -1)
    if len(spheres):
        c = spheres[:, :3].astype(np.float64)[None]
        r = spheres[:, 3].astype(np.float64)[None]
        oc = o - c
        a = np.einsum("rk,rk->r", d[:, 0], d[:, 0])[:, None]
        b = np.einsum("rsk,rk->rs", oc, d[:, 0])
        cc = np.einsum("rsk,rsk->rs", oc, oc) - r * r
        disc = b * b - a * cc
        with np.errstate(invalid="ignore"):
            s = np.sqrt(disc)
            t0, t1 = (-b - s) / a, (-b + s) / a
        t = np.where(t0 > 0, t0, t1)
        t = np.where((disc >= 0) & (t > 0), t, np.inf)
        sid = t.argmin(1)
        st = t[np.arange(len(o)), sid]
        closer = st < best_t
        best_t = np.where(closer, st, best_t)
        best_id = np.where(closer, sid, best_id)
        best_kind = np.where(closer, 1, best_kind)
    return best_t, best_id, best_kind


def box_entry(lo, hi, o, d):
    """One box's slab test for the ray o + t·d, t ≥ 0, written out per axis: the entry distance (0
    inside), inf on a miss."""
    t_in, t_out = 0.0, math.inf
    for a in range(3):
        if d[a] == 0:
            if not lo[a] <= o[a] <= hi[a]:
                return math.inf
            continue
        t0, t1 = (lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]
        t_in, t_out = max(t_in, min(t0, t1)), min(t_out, max(t0, t1))
    return t_in if t_in <= t_out else math.inf


def pick_by_brute_force(data, o, d, t_hit, depths, leaves_only):
    """The node Pick Box must pick, by a loop over every node (bvhlab.inspect.NodeData): of the
    boxes in the depth range (leaves only if asked) entered no later than t_hit, the deepest, then
    the first entered, then the lowest index; None when there is none."""
    best = None
    for n in range(len(data)):
        if not depths[0] <= data.depth[n] <= depths[1] or (leaves_only and data.left[n] >= 0):
            continue
        t = box_entry(data.lo[n].astype(float), data.hi[n].astype(float), o, d)
        if math.isinf(t) or t > t_hit * (1 + 1e-4):  # not entered, or after the hit: the box around the
            continue  # hit triangle is entered at t_hit, give or take rounding
        key = (-int(data.depth[n]), t, n)
        if best is None or key < best:
            best = key
    return None if best is None else best[2]


def check_tree_layout(bvh, tris: np.ndarray) -> None:
    """A tree over triangles `tris` is whole: leaves hold their triangles' boxes, every triangle
    once, inner nodes hold their children, the second child follows the first's subtree, skips
    are right (docs/design.md "Tree layout")."""
    nodes, refs, skip, leaf = bvh.nodes, bvh.refs, bvh.skip, bvh.is_leaf
    lo, hi = nodes["lo"], nodes["hi"]
    # leaves hold their triangles' boxes
    counts = np.where(leaf, nodes["info"], 0)
    owner = np.repeat(np.flatnonzero(leaf), counts[leaf])
    slots = np.concatenate([np.arange(s, s + c) for s, c in zip(nodes["index"][leaf], counts[leaf])])
    assert np.all(lo[owner] <= tris[refs[slots]].min(1)) and np.all(hi[owner] >= tris[refs[slots]].max(1))
    assert sorted(refs.tolist()) == list(range(len(tris)))
    # inner nodes hold both children; the second child follows the first's subtree; skips are right
    inner = np.flatnonzero(~leaf)
    first, second = inner + 1, nodes["index"][inner]
    for child in (first, second):
        assert np.all(lo[inner] <= lo[child]) and np.all(hi[inner] >= hi[child])
    np.testing.assert_array_equal(skip[first], second)
    np.testing.assert_array_equal(skip[inner], skip[second])


def subtree_slots(bvh):
    """(first, count) of each node's subtree in leaf order, from the nodes alone."""
    nodes, leaf = bvh.nodes, bvh.is_leaf
    first = np.where(leaf, nodes["index"], 0).astype(np.int64)
    count = np.where(leaf, nodes["info"], 0).astype(np.int64)
    for i in range(len(nodes) - 1, -1, -1):
        if not leaf[i]:
            first[i], count[i] = first[i + 1], count[i + 1] + count[nodes["index"][i]]
    return first, count


# -- a float64 Whitted tracer: the shading model of shaders/tracer/shade.glsl, written again --------
AMBIENT, SPECULAR, SHININESS = 0.1, 0.25, 48.0  # shade_colors.glsl's constants


def _unit(v):
    return v / np.linalg.norm(v)


class Whitted64:
    """The tracer's image, worked out in float64 by brute force over a small scene's primitives:
    reflection, refraction (Snell, total internal reflection into reflection), one shadow ray to
    the point light attenuated by the transparencies it crosses, the sky for misses. A secondary
    ray starts `eps` off its surface, which float64 resolves far below any object's size."""

    def __init__(self, scene, max_depth, eps=1e-6):
        self.spheres = np.asarray(scene.spheres, np.float64).reshape(-1, 4)
        self.tris = np.asarray(scene.triangles, np.float64).reshape(-1, 3, 3)
        self.materials = [(np.asarray(m.color, float), m.reflective, m.transparent, m.ior) for m in scene.materials]
        self.sphere_material, self.tri_material = list(scene.sphere_material), list(scene.tri_material)
        light = scene.light
        self.light, self.light_color = np.asarray(light.position, float), np.asarray(light.color) * light.intensity
        self.sky, self.eps, self.max_depth = np.asarray(scene.sky, float), eps, max_depth

    def _crossings(self, o, d):
        """(t, kind, index) of every crossing of the line o + t·d with a primitive."""
        for i, s in enumerate(self.spheres):
            f = o - s[:3]
            b, c = f @ d, f @ f - s[3] ** 2
            disc = b * b - c
            if disc >= 0:
                yield from ((t, "s", i) for t in (-b - math.sqrt(disc), -b + math.sqrt(disc)))
        for i, v in enumerate(self.tris):  # Möller–Trumbore
            e1, e2 = v[1] - v[0], v[2] - v[0]
            p = np.cross(d, e2)
            det = e1 @ p
            if det == 0:
                continue
            s = o - v[0]
            u = (s @ p) / det
            q = np.cross(s, e1)
            w = (d @ q) / det
            if u >= 0 and w >= 0 and u + w <= 1:
                yield (e2 @ q) / det, "t", i

    def _material(self, kind, i):
        return self.materials[(self.sphere_material if kind == "s" else self.tri_material)[i]]

    def _direct(self, p, n, d, albedo):
        to_light = self.light - p
        dist = np.linalg.norm(to_light)
        to_l = to_light / dist
        lambert, color = n @ to_l, albedo * AMBIENT
        if lambert <= 0:
            return color
        o = p + n * self.eps
        transmission = np.prod([self._material(k, i)[2] for t, k, i in self._crossings(o, to_l) if 0 < t < dist])
        if transmission <= 0:
            return color
        highlight = max(n @ _unit(to_l - d), 0) ** SHININESS * SPECULAR
        return color + self.light_color * transmission * (1 - AMBIENT) * (albedo * lambert + highlight)

    def trace(self, o, d):
        color, rays = np.zeros(3), [(o, d, np.ones(3), 0)]
        while rays:
            o, d, weight, depth = rays.pop()
            hits = [h for h in self._crossings(o, d) if h[0] > 0]
            if not hits:
                color += weight * self.sky
                continue
            t, kind, i = min(hits, key=lambda h: h[0])
            p = o + d * t
            v = self.tris[i] if kind == "t" else None
            n = _unit(p - self.spheres[i][:3] if kind == "s" else np.cross(v[1] - v[0], v[2] - v[0]))
            entering = n @ d < 0
            n = n if entering else -n
            albedo, reflective, transparent, ior = self._material(kind, i)
            opaque = max(1 - reflective - transparent, 0)
            if opaque > 0:
                color += weight * opaque * self._direct(p, n, d, albedo)
            if depth >= self.max_depth:
                continue
            if transparent > 0:
                eta, cos_i = (1 / ior if entering else ior), -(n @ d)
                k = 1 - eta * eta * (1 - cos_i * cos_i)
                if k < 0:
                    reflective += transparent
                else:
                    refracted = _unit(eta * d + (eta * cos_i - math.sqrt(k)) * n)
                    rays.append((p - n * self.eps, refracted, weight * transparent, depth + 1))
            if reflective > 0:
                rays.append((p + n * self.eps, d - 2 * (d @ n) * n, weight * reflective, depth + 1))
        return color

    def render(self, camera, width, height):
        """One sample at each pixel's centre through a pinhole camera (camera.glsl's perspective)."""
        pos = np.asarray(camera.position, float)
        forward = _unit(np.asarray(camera.look_at, float) - pos)
        right = _unit(np.cross(forward, _unit(np.asarray(camera.up, float))))
        up = np.cross(right, forward)
        h = 2 * math.tan(math.radians(camera.fov_y) / 2)
        w = h * width / height
        image = np.zeros((height, width, 3))
        for y in range(height):
            for x in range(width):
                d = _unit(forward + right * (-w / 2 + (x + 0.5) * w / width) + up * (h / 2 - (y + 0.5) * h / height))
                image[y, x] = self.trace(pos, d)
        return image


def camera_ray_hits(scene, tree, width: int, height: int, options) -> dict:
    """What `tree.intersect` (a Bvh or an InstancedBvh: independent of the tracer's walk) hits with
    each of the tracer's own camera rays (bvhlab._core.pixel_ray, each between its clipping planes):
    the hit fields, each shaped (height, width, n·n) for n×n samples a pixel."""
    import bvhlab
    from bvhlab._render_scene import SceneCache
    from bvhlab._render_settings import render_settings

    settings = render_settings(scene, tree, width, height, options)
    render_scene = SceneCache().get(scene, tree)
    n2 = options.samples_per_axis**2
    rays = [
        bvhlab._core.pixel_ray(render_scene, settings, x, y, k)
        for y in range(height)
        for x in range(width)
        for k in range(n2)
    ]
    origins, directions = (np.array([r[i] for r in rays], np.float32) for i in (0, 1))
    hits = [
        tree.intersect(origins[i : i + 1], directions[i : i + 1], tmin=tmin, tmax=tmax)
        for i, (_, _, tmin, tmax) in enumerate(rays)
    ]
    return {key: np.concatenate([h[key] for h in hits]).reshape(height, width, n2) for key in hits[0]}
