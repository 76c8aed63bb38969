"""Derives samples/head/head.obj from the MakeHuman base mesh hm08 (CC0 1.0; issue 41).

    python3 scripts/make_head.py PATH/TO/base.obj samples/head/head.obj

What it does, in order:
1. reads the skin surface (group `body`, quads) and the eye joints (`joint-l-eye`, `joint-r-eye`);
2. keeps head and neck: the quads whose four corners lie above `NECK_CUT_DM` (one boundary loop
   remains, around the neck; hm08's eye sockets and mouth are closed pockets, not holes);
3. closes the neck with a fan of triangles around the loop's centroid;
4. one Catmull-Clark subdivision (every face becomes quads), so the close-up of figure 7 (0.09 mm
   a pixel) sees no facets, and area-weighted vertex normals;
5. converts decimetres to millimetres, origin between the eyes' centres, +y up, face toward +z;
6. adds an eyeball (a UV sphere, group `eyes`) in each socket, just inside the lids;
7. lays out UVs for a face map (`unwrap`): a spherical projection about the head's centre, the
   seam at the back (u = 0 = 1), the crown at v = 0 (top of the image); the azimuth and polar
   angle are warped so the face (forehead to chin, ear to ear) takes the middle of the map, where
   samples/face/layout.toml puts its regions; the pockets (which fold over in the projection)
   relaxed into discs inside their rims, then moved with the eyeballs one map width to the right
   (u + 1), so texture-space passes give them no texel of the skin's.

Needs numpy. Prints the counts and the face's texel density; `crates/render/tests/render/head.rs`
checks the committed result.
"""
import sys

import numpy as np

# Below the jaw and above the collarbones (hm08 is in decimetres, the chin near y = 6.6).
NECK_CUT_DM = 5.9
MM_PER_DM = 100.0
# Eyeball radius as a share of the distance from the eye's centre to the nearest lid vertex.
EYE_FILL = 0.97
# Warps of the projection (see `unwrap`), piecewise linear: azimuth (degrees from +z toward +x)
# to u, ear to ear in 80 % of the map; polar angle (degrees from +y) to v, hairline to chin in 87 %.
AZIMUTH_KNOTS = ([-180.0, -90.0, 90.0, 180.0], [0.0, 0.1, 0.9, 1.0])
POLAR_KNOTS = ([0.0, 35.0, 140.0, 180.0], [0.0, 0.05, 0.92, 1.0])
# Centre of the projection relative to the eyes' midpoint, mm (behind the eyes, at the nose).
CENTRE_MM = np.array([0.0, -25.0, -75.0])


def read_obj(path):
    """Positions, the `body` quads (0-based) and the eye joints' centres of an OBJ file."""
    positions, groups, group = [], {}, None
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("v "):
                positions.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f "):
                corners = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
                groups.setdefault(group, []).append(corners)
    positions = np.array(positions)
    eyes = [positions[sorted({i for f in groups[g] for i in f})].mean(0) for g in ("joint-r-eye", "joint-l-eye")]
    return positions, groups["body"], eyes


def head_and_neck(positions, quads):
    """The quads above the neck cut, re-indexed, and their positions."""
    kept = [q for q in quads if positions[q, 1].min() > NECK_CUT_DM]
    used = sorted({i for q in kept for i in q})
    index = {old: new for new, old in enumerate(used)}
    return positions[used], [[index[i] for i in q] for q in kept]


def boundary_loop(faces):
    """The one boundary loop, as directed edges in face order; fails if there is not exactly one."""
    directed = {(a, b) for f in faces for a, b in zip(f, f[1:] + f[:1])}
    open_edges = {a: b for a, b in directed if (b, a) not in directed}
    start = next(iter(open_edges))
    loop, at = [start], open_edges[start]
    while at != start:
        loop.append(at)
        at = open_edges[at]
    if len(loop) != len(open_edges):
        sys.exit(f"expected one boundary loop, found {len(open_edges)} boundary edges over several")
    return loop


def close_neck(positions, faces):
    """Adds a fan of triangles around the neck loop's centroid, wound like the skin."""
    loop = boundary_loop(faces)
    centre = len(positions)
    positions = np.vstack([positions, positions[loop].mean(0)])
    # The loop runs along the skin faces' edges a -> b; the cap uses them as b -> a.
    fan = [[loop[(k + 1) % len(loop)], loop[k], centre] for k in range(len(loop))]
    return positions, faces + fan, len(loop)


def edge_table(faces):
    """Each undirected edge's index and the faces on either side."""
    edges, sides = {}, []
    for fi, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            key = (min(a, b), max(a, b))
            if key not in edges:
                edges[key] = len(sides)
                sides.append([])
            sides[edges[key]].append(fi)
    if any(len(s) != 2 for s in sides):
        sys.exit("the closed head is not a closed 2-manifold")
    return edges, sides


def catmull_clark(positions, faces):
    """One Catmull-Clark step on a closed mesh: every n-gon becomes n quads."""
    edges, sides = edge_table(faces)
    face_pts = np.array([positions[f].mean(0) for f in faces])
    keys = np.array(list(edges.keys()))
    order = np.array(list(edges.values()))
    edge_pts = np.empty((len(sides), 3))
    mids = positions[keys].mean(1)
    edge_pts[order] = (positions[keys[:, 0]] + positions[keys[:, 1]] + face_pts[[sides[e][0] for e in order]]
                       + face_pts[[sides[e][1] for e in order]]) / 4.0
    moved = move_vertices(positions, faces, face_pts, keys, mids)
    new_positions = np.vstack([moved, edge_pts, face_pts])
    ne, nv = len(sides), len(positions)
    quads = []
    for fi, f in enumerate(faces):
        n = len(f)
        for k in range(n):
            a, b, prev = f[k], f[(k + 1) % n], f[k - 1]
            e_next = nv + edges[(min(a, b), max(a, b))]
            e_prev = nv + edges[(min(prev, a), max(prev, a))]
            quads.append([a, e_next, nv + ne + fi, e_prev])
    return new_positions, quads


def move_vertices(positions, faces, face_pts, keys, mids):
    """Catmull-Clark's vertex rule: (F + 2R + (n - 3) P) / n."""
    n = len(positions)
    face_sum, face_count = np.zeros((n, 3)), np.zeros(n)
    for fi, f in enumerate(faces):
        for i in f:
            face_sum[i] += face_pts[fi]
            face_count[i] += 1
    mid_sum, valence = np.zeros((n, 3)), np.zeros(n)
    for end in (0, 1):
        np.add.at(mid_sum, keys[:, end], mids)
        np.add.at(valence, keys[:, end], 1)
    f_avg, r_avg = face_sum / face_count[:, None], mid_sum / valence[:, None]
    k = valence[:, None]
    return (f_avg + 2.0 * r_avg + (k - 3.0) * positions) / k


def triangles(faces):
    """Faces split into fans from their first corner (for normals and measures)."""
    return np.array([[f[0], f[k], f[k + 1]] for f in faces for k in range(1, len(f) - 1)])


def vertex_normals(positions, tris):
    """Area-weighted vertex normals."""
    cross = np.cross(positions[tris[:, 1]] - positions[tris[:, 0]], positions[tris[:, 2]] - positions[tris[:, 0]])
    normals = np.zeros_like(positions)
    for corner in range(3):
        np.add.at(normals, tris[:, corner], cross)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def eyeball(centre, radius, first, rows=16, columns=32):
    """A UV sphere (positions, normals, quads and fan triangles indexed from `first`), poles on z."""
    pts = [centre + radius * np.array([0.0, 0.0, 1.0])]
    for j in range(1, rows):
        theta = np.pi * j / rows
        for i in range(columns):
            phi = 2.0 * np.pi * i / columns
            pts.append(centre + radius * np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                                   np.cos(theta)]))
    pts.append(centre - radius * np.array([0.0, 0.0, 1.0]))
    pts = np.array(pts)
    ring = lambda j, i: first + 1 + (j - 1) * columns + i % columns  # noqa: E731
    faces = [[first, ring(1, i), ring(1, i + 1)] for i in range(columns)]
    for j in range(1, rows - 1):
        faces += [[ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)] for i in range(columns)]
    last = first + len(pts) - 1
    faces += [[ring(rows - 1, i), last, ring(rows - 1, i + 1)] for i in range(columns)]
    return pts, (pts - centre) / radius, faces


def unwrap(positions):
    """Per-vertex (u, v), v = 0 at the top of the image (skinkit's convention)."""
    d = positions - CENTRE_MM
    azimuth = np.degrees(np.arctan2(d[:, 0], d[:, 2]))
    polar = np.degrees(np.arccos(np.clip(d[:, 1] / np.linalg.norm(d, axis=1), -1.0, 1.0)))
    return np.stack([np.interp(azimuth, *AZIMUTH_KNOTS), np.interp(polar, *POLAR_KNOTS)], axis=1)


def uv_signed_areas(uv, tris):
    """Twice each triangle's signed area in (u, v); negative for a counter-clockwise face, since v
    runs down the image."""
    e1, e2 = uv[tris[:, 1]] - uv[tris[:, 0]], uv[tris[:, 2]] - uv[tris[:, 0]]
    return e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]


def relax_folds(uv, faces, rings=8, steps=2000):
    """Pockets that face the projection's centre (the eye sockets behind the eyeballs, the mouth,
    the nostrils, the backs of the ears) fold over in the projection. Their vertices, grown by
    `rings`, are moved to the average of their neighbours until still (Tutte's embedding: inside
    a convex rim no triangle flips), the rest held fixed. The seam's neighbourhood is left alone.
    Returns the UVs, the number of relaxed vertices and which faces are pockets (all corners in
    a fold or enclosed by one: out of sight, inside the head)."""
    tris = triangles(faces)
    front = (uv[tris, 0].min(1) > 0.05) & (uv[tris, 0].max(1) < 0.95)
    fold = np.zeros(len(uv), bool)
    fold[tris[front & (uv_signed_areas(uv, tris) >= 0.0)].ravel()] = True
    edges = np.array([(f[k], f[(k + 1) % len(f)]) for f in faces for k in range(len(f))])
    # Only the face's folds are pockets; the backs of the ears fold too, but are in sight.
    inside = fill_islands(fold & (np.abs(uv[:, 0] - 0.5) < 0.3), edges)
    pockets = np.array([inside[f].all() for f in faces])
    free = fold
    for _ in range(rings):
        grown = free.copy()
        grown[edges[free[edges[:, 0]], 1]] = True
        free = grown
    free = fill_islands(free, edges)
    return harmonic(uv, edges, free, steps), int(free.sum()), pockets


def fill_islands(free, edges):
    """`free` and every island of fixed vertices it encloses: only the largest fixed region (the
    outer skin) stays fixed, so each relaxed patch is a disc with a fixed rim."""
    label = np.full(len(free), -1)
    fixed_edges = edges[~free[edges[:, 0]] & ~free[edges[:, 1]]]
    neighbours = [[] for _ in free]
    for a, b in fixed_edges:
        neighbours[a].append(b)
    sizes = []
    for start in np.where(~free)[0]:
        if label[start] >= 0:
            continue
        label[start], stack, size = len(sizes), [start], 0
        while stack:
            at = stack.pop()
            size += 1
            for n in neighbours[at]:
                if label[n] < 0:
                    label[n] = len(sizes)
                    stack.append(n)
        sizes.append(size)
    return free | ((label >= 0) & (label != int(np.argmax(sizes))))


def harmonic(uv, edges, free, steps):
    """`uv` with the `free` vertices at the average of their neighbours, the others fixed: the
    graph Laplacian's system on the free vertices, solved by conjugate gradients."""
    degree = np.zeros(len(uv))
    np.add.at(degree, edges[:, 0], 1.0)

    def laplacian(x):
        """(D - A) x restricted to the free vertices (x is zero on the fixed ones)."""
        total = np.zeros_like(x)
        np.add.at(total, edges[:, 0], x[edges[:, 1]])
        return np.where(free[:, None], degree[:, None] * x - total, 0.0)

    fixed = np.where(free[:, None], 0.0, uv)
    rhs = -laplacian_full(fixed, edges, degree, free)
    x = np.where(free[:, None], uv, 0.0)
    r = rhs - laplacian(x)
    p, rr = r.copy(), (r * r).sum(0)
    for _ in range(steps):
        ap = laplacian(p)
        alpha = rr / np.maximum((p * ap).sum(0), 1e-30)
        x, r = x + alpha * p, r - alpha * ap
        rr_next = (r * r).sum(0)
        if rr_next.max() < 1e-20:
            break
        p, rr = r + rr_next / rr * p, rr_next
    return np.where(free[:, None], x, uv)


def laplacian_full(x, edges, degree, rows):
    """(D - A) x on the rows `rows` (zero elsewhere)."""
    total = np.zeros_like(x)
    np.add.at(total, edges[:, 0], x[edges[:, 1]])
    return np.where(rows[:, None], degree[:, None] * x - total, 0.0)


def split_seam(uv, faces):
    """Per-corner UV indices; a face across the back seam gets copies of its small-u corners at
    u + 1, so no face spans the map (they sit just right of the map, out of sight)."""
    uvs, corner_uv, copies = list(uv), [], {}
    for f in faces:
        us = uv[f, 0]
        if us.max() - us.min() <= 0.5:
            corner_uv.append(list(f))
            continue
        row = []
        for i in f:
            if uv[i, 0] < 0.5:
                if i not in copies:
                    copies[i] = len(uvs)
                    uvs.append(uv[i] + np.array([1.0, 0.0]))
                row.append(copies[i])
            else:
                row.append(i)
        corner_uv.append(row)
    return np.array(uvs), corner_uv


def off_the_map(uv, corner_uv, hidden):
    """The `hidden` faces (pockets, eyeballs) get their own copies of their UVs one map width to
    the right (u + 1): a UV seam along the lips and the lids, where it is out of sight. Sampled
    with a repeating sampler they read the same texels as before, but texture-space passes
    (diffusion, the reference), which draw into the map, leave them out, so their squeezed
    triangles no longer share texels with the lips and lids."""
    uvs, copies, rows = list(uv), {}, []
    for row, hide in zip(corner_uv, hidden):
        if not hide:
            rows.append(row)
            continue
        moved = []
        for t in row:
            if t not in copies:
                copies[t] = len(uvs)
                uvs.append(uv[t] + np.array([1.0, 0.0]))
            moved.append(copies[t])
        rows.append(moved)
    return np.array(uvs), rows


def density(positions, uv, corner_uv, faces, size=(2048, 1024)):
    """Millimetres of surface per texel of a `size` map, per triangle (sqrt of the area ratio)."""
    tris = triangles(faces)
    tuv = triangles(corner_uv)
    p, t = positions[tris], uv[tuv] * np.array(size)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    # v runs down the image, so a counter-clockwise face has a negative signed area in (u, v).
    texels = -0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    # mm per texel along u and along v: the lengths of the surface's derivatives by texel.
    inv = 1.0 / np.where(np.abs(texels) > 1e-12, -2.0 * texels, 1e-12)
    d = p[:, 1:] - p[:, :1]
    dpdu = (d[:, 0] * e2[:, 1:2] - d[:, 1] * e1[:, 1:2]) * inv[:, None]
    dpdv = (d[:, 1] * e1[:, 0:1] - d[:, 0] * e2[:, 0:1]) * inv[:, None]
    stretch = np.stack([np.linalg.norm(dpdu, axis=1), np.linalg.norm(dpdv, axis=1)], axis=1)
    return np.sqrt(area / np.maximum(texels, 1e-12)), texels, p.mean(1), stretch


def write_obj(path, positions, normals, uv, groups):
    """The head as OBJ: shared v and vn, vt split at the seam, v flipped to OBJ's bottom origin;
    `groups` are (name, [(face, its UV indices)])."""
    with open(path, "w", encoding="utf-8", newline="\n") as out:
        out.write("# skinkit sample head (mm, +y up, face toward +z), derived by scripts/make_head.py from the "
                  "MakeHuman base mesh hm08 (CC0 1.0)\n")
        out.writelines(f"v {x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in positions)
        out.writelines(f"vt {u:.5f} {1.0 - v:.5f}\n" for u, v in uv)
        out.writelines(f"vn {x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in normals)
        for name, faces in groups:
            out.write(f"g {name}\n")
            for f, c in faces:
                out.write("f " + " ".join(f"{i + 1}/{t + 1}/{i + 1}" for i, t in zip(f, c)) + "\n")


def add_eyes(positions, normals, eye_centres):
    """Appends both eyeballs; returns positions, normals and their faces."""
    faces = []
    for centre in eye_centres:
        radius = EYE_FILL * np.linalg.norm(positions - centre, axis=1).min()
        pts, nrm, f = eyeball(centre, radius, len(positions))
        positions, normals, faces = np.vstack([positions, pts]), np.vstack([normals, nrm]), faces + f
    return positions, normals, faces


def eye_uvs(uv, positions, eye_centres, first, faces, pockets):
    """Each eyeball's UVs: a disc about its front pole (distance from the pole to radius, turning
    like the skin's u and v), inside the socket's relaxed pocket so that no eyeball texel is a
    skin texel (texture-space passes would otherwise spread the dark back of the ball over the
    lids)."""
    uv = uv.copy()
    skin = np.zeros(len(positions), bool)
    skin[[i for f, p in zip(faces, pockets) if not p for i in f]] = True
    socket = np.zeros(len(positions), bool)
    socket[[i for f, p in zip(faces, pockets) if p for i in f]] = True
    count = (len(positions) - first) // len(eye_centres)
    for k, centre in enumerate(eye_centres):
        ball = np.arange(first + k * count, first + (k + 1) * count)
        near = socket & ~skin & (np.linalg.norm(positions - centre, axis=1) < 25.0)
        middle = uv[near].mean(0)
        reach = 0.8 * np.linalg.norm(uv[skin] - middle, axis=1).min()
        d = (positions[ball] - centre) / np.linalg.norm(positions[ball] - centre, axis=1, keepdims=True)
        angle = np.arccos(np.clip(d[:, 2], -1.0, 1.0)) / np.pi
        turn = np.arctan2(d[:, 1], d[:, 0])
        uv[ball] = middle + reach * angle[:, None] * np.stack([np.cos(turn), -np.sin(turn)], axis=1)
    return uv


def main(source, target):
    positions, quads, eyes = read_obj(source)
    positions, faces = head_and_neck(positions, quads)
    positions, faces, neck = close_neck(positions, faces)
    positions, faces = catmull_clark(positions, faces)
    origin = (eyes[0] + eyes[1]) / 2.0
    positions = (positions - origin) * MM_PER_DM
    eyes = [(e - origin) * MM_PER_DM for e in eyes]
    normals = vertex_normals(positions, triangles(faces))
    skin_vertices = len(positions)
    positions, normals, eye_faces = add_eyes(positions, normals, eyes)
    uv, relaxed, pockets = relax_folds(unwrap(positions), faces)
    uv = eye_uvs(uv, positions, eyes, skin_vertices, faces, pockets)
    uv, corner_uv = split_seam(uv, faces + eye_faces)
    uv, corner_uv = off_the_map(uv, corner_uv, list(pockets) + [True] * len(eye_faces))
    skin = [(f, c) for f, c, p in zip(faces, corner_uv, pockets) if not p]
    inner = [(f, c) for f, c, p in zip(faces, corner_uv, pockets) if p]
    eye = list(zip(eye_faces, corner_uv[len(faces):]))
    write_obj(target, positions, normals, uv, [("skin", skin), ("pockets", inner), ("eyes", eye)])
    faces, corners = [f for f, _ in skin], [c for _, c in skin]
    mm, texels, centres, stretch = density(positions, uv, corners, faces)
    low, high = positions[:skin_vertices].min(0), positions[:skin_vertices].max(0)
    print(f"{target}: {len(positions)} vertices ({skin_vertices} skin), {len(faces)} skin quads, "
          f"{len(inner)} of them pockets, {len(eye_faces)} eye faces, {len(uv)} uvs ({relaxed} relaxed); neck loop of {neck}; bounds {low.round(1)} .. {high.round(1)} mm")
    face = (centres[:, 2] > -5.0) & (centres[:, 1] > -110.0) & (centres[:, 1] < 70.0) & (np.abs(centres[:, 0]) < 65.0)
    q = np.percentile(mm[face], [0, 1, 50, 99, 100])
    s = np.percentile(stretch[face], [1, 50, 99], axis=0)
    print(f"face ({face.sum()} triangles): mm per texel of 2048x1024 min/p1/median/p99/max {q.round(3)}; "
          f"flipped or zero {(texels[face] <= 0).sum()}; mm per texel along u, v (p1, median, p99) {s.round(3).tolist()}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: make_head.py BASE.OBJ OUT.OBJ")
    main(sys.argv[1], sys.argv[2])
