"""Contact geometry of boundary primitives, in the boundary's own frame.

Every boundary is made of primitives. A primitive is one row of a float table ``par``
(``PAR_WIDTH`` columns, layout per kind below) plus its kind code, all in the local frame
of its boundary (the frame moves with the boundary's motion; the step transforms element
centres into it). :func:`closest` returns, for a sphere centre ``(x, y, z)``:

    dist     signed distance from the centre to the primitive's surface (> 0 outside;
             the overlap of a sphere of radius r is r - dist)
    nx,ny,nz unit normal from the surface towards the centre (the direction of the force
             on the sphere); shorter than 1 for a ring contact of AXI, when its length
             scales the force
    feature  0 face, 1-3 edge (v0v1, v1v2, v2v0), 4-6 vertex v0-v2 (triangles); JOINED (7)
             beyond a joined pipe end (no force); 0 else

Kinds and their ``par`` columns:

PLANE (0)     point p [0:3], unit normal n [3:6]. dist = (x - p).n, one-sided (the normal
              points into the domain; a centre more than its radius behind is ignored).
SLAB (1)      finite wall: centre c [0:3], unit axes u [3:6], v [6:9], half extents a [9],
              b [10] and half thickness h [11]. A rectangular box: the closest point of the
              box; edges and corners are rounded (distance to the closest point), a centre
              inside the box takes the nearest face (dist < 0).
AXI (2)       surface of revolution of a straight meridian segment: axis origin o [0:3],
              unit axis a [3:6], segment (rho0, z0) [6:8] to (rho1, z1) [8:10], half
              thickness h [10], joined ends [11] (bit 0: z < z0, bit 1: z > z1). A frustum
              wall (tube, cone), an annulus or a disc (rho0 = 0): dist = distance in the
              meridian plane (rho, z) to the segment, minus h; both sides touch, the
              segment's ends are rounded edges, except at an end joined to another pipe
              piece: a centre beyond it belongs to the next piece (no contact here). A
              sphere meeting the surface in a ring (centre near the axis) gets one contact
              integrated over the ring: the normal is then shorter than 1 and scales the
              force (:func:`axi_distance`).
TORUS (3)     bend: centre c [0:3], unit axis a [3:6] (normal of the bend plane), unit e1
              [6:9] (direction of angle 0; e2 = a x e1), bend radius R [9], pipe radius rp
              [10], bend angle theta [11], half thickness h [12], joined ends [13] (bit 0:
              angle 0, bit 1: angle theta; as for AXI). The pipe wall of the torus
              segment 0 <= phi <= theta: the centre circle point C(phi) at the clamped angle,
              dist = |(rho' - rp, w_t)| - h in the pipe's cross-section plane, so the pipe's
              end rings are rounded edges; inside and outside both touch.
TRIANGLE (4)  vertices v0 [0:3], v1 [3:6], v2 [6:9], half thickness h [9], unit face
              normal [10:13], dual in-plane vectors g1 [13:16], g2 [16:19] (g_i . e_j =
              delta_ij for the edges e1 = v1 - v0, e2 = v2 - v0, g_i . n = 0; zero for a
              row written without them), smallest altitude [19] (zero: unknown, height bound only).
              Closest point of the triangle (Ericson, Real-Time Collision Detection, 2005,
              5.1.5) with its feature; both sides touch. A
              centre over the triangle's inside (barycentric coordinates s = (x - v0) . g1,
              t = (x - v0) . g2 with s > 0, t > 0, s + t < 1) is a face contact at the
              height (x - v0) . n, found with three dot products before that test.
SIEVE (5)     screen plate of a hole-clearance model: centre c [0:3], axes u [3:6], v [6:9],
              half extents a [9], b [10], half thickness h [11], hole width wh [12], pitch
              p [13] (hole + bar; holes centred at c + (i u + j v) p), hole shape [14]
              (0 square, 1 round), model [15] (1 radius-dependent, 2 fixed), zeta [16].
              Alkhaldi 2007, sec. 4.3.3, eqs. 4.20-4.24: a sphere smaller than the hole
              whose centre lies over the reduced hole (half width wh/2 - b, b = zeta
              (wh/2 - r) for model 1, b = zeta wh/2 for model 2) falls through; any other
              sphere meets the plate (faces at |w| = h, rounded outline). Extension for
              moving screens: a sphere passing a hole (centre over the reduced hole, or over
              the hole and already within 3/4 of its radius of the face) meets the rim of
              the real hole (in-plane gap to the rim combined with the depth), so one that
              drifts while passing is guided by the rim instead of being thrown back through
              the plane; a rim it does not reach exerts nothing, as in the thesis. The
              exact sieve is a triangle mesh (:class:`dpm.boundaries.sieve.Sieve`).
"""

import math

from .config import inline_jit, jit

PAR_WIDTH = 20
PLANE = 0
SLAB = 1
AXI = 2
TORUS = 3
TRIANGLE = 4
SIEVE = 5

# feature codes of triangle contacts
FACE = 0
#: feature of a surface of revolution or torus contact beyond an end joined to another
#: pipe piece: listed as a candidate (distance as usual) but exerting no force
JOINED = 7


@inline_jit
def _unit_perpendicular(ax, ay, az):
    """Some unit vector perpendicular to the unit vector a."""
    if abs(ax) < 0.9:
        px, py, pz = 0.0, -az, ay  # a x (1, 0, 0)
    else:
        px, py, pz = az, 0.0, -ax  # a x (0, 1, 0)
    s = 1.0 / math.sqrt(px * px + py * py + pz * pz)
    return px * s, py * s, pz * s


@inline_jit
def plane_distance(p, x, y, z):
    nx = p[3]
    ny = p[4]
    nz = p[5]
    return (x - p[0]) * nx + (y - p[1]) * ny + (z - p[2]) * nz, nx, ny, nz


@inline_jit
def plate_coordinates(p, x, y, z):
    """Coordinates (s, t, w) of a point in a plate's axes u = p[3:6], v = p[6:9],
    w = u x v about its centre p[0:3], and those axes."""
    dx = x - p[0]
    dy = y - p[1]
    dz = z - p[2]
    ux, uy, uz = p[3], p[4], p[5]
    vx, vy, vz = p[6], p[7], p[8]
    wx = uy * vz - uz * vy
    wy = uz * vx - ux * vz
    wz = ux * vy - uy * vx
    return (dx * ux + dy * uy + dz * uz, dx * vx + dy * vy + dz * vz,
            dx * wx + dy * wy + dz * wz, ux, uy, uz, vx, vy, vz, wx, wy, wz)


@inline_jit
def slab_distance(p, x, y, z):
    s, t, w, ux, uy, uz, vx, vy, vz, wx, wy, wz = plate_coordinates(p, x, y, z)
    a = p[9]
    b = p[10]
    h = p[11]
    cs = min(max(s, -a), a)
    ct = min(max(t, -b), b)
    cw = min(max(w, -h), h)
    es = s - cs
    et = t - ct
    ew = w - cw
    d2 = es * es + et * et + ew * ew
    if d2 > 0.0:
        d = math.sqrt(d2)
        inv = 1.0 / d
        es *= inv
        et *= inv
        ew *= inv
        return (d, es * ux + et * vx + ew * wx, es * uy + et * vy + ew * wy,
                es * uz + et * vz + ew * wz)
    # inside: leave through the nearest face
    gs = a - abs(s)
    gt = b - abs(t)
    gw = h - abs(w)
    if gw <= gs and gw <= gt:
        sg = 1.0 if w >= 0.0 else -1.0
        return -gw, sg * wx, sg * wy, sg * wz
    if gs <= gt:
        sg = 1.0 if s >= 0.0 else -1.0
        return -gs, sg * ux, sg * uy, sg * uz
    sg = 1.0 if t >= 0.0 else -1.0
    return -gt, sg * vx, sg * vy, sg * vz


@inline_jit
def _segment_2d(r, z, r0, z0, r1, z1):
    """Closest point of the segment (r0, z0)-(r1, z1) to (r, z): (er, ez, d) with (er, ez)
    the unit vector from that point to (r, z) and d the distance; on the segment the
    segment's normal (turned +90 degrees from its direction) is returned with d = 0."""
    sr = r1 - r0
    sz = z1 - z0
    ll = sr * sr + sz * sz
    t = 0.0
    if ll > 0.0:
        t = ((r - r0) * sr + (z - z0) * sz) / ll
        t = min(max(t, 0.0), 1.0)
    er = r - (r0 + t * sr)
    ez = z - (z0 + t * sz)
    d = math.sqrt(er * er + ez * ez)
    if d > 0.0:
        return er / d, ez / d, d
    if ll > 0.0:
        il = 1.0 / math.sqrt(ll)
        return -sz * il, sr * il, 0.0
    return 1.0, 0.0, 0.0


#: azimuths of the ring quadrature of a surface-of-revolution contact (axi_distance)
RING_SAMPLES = 16
_RING_COS = tuple(math.cos(2.0 * math.pi * k / RING_SAMPLES) for k in range(RING_SAMPLES))
_RING_SIN = tuple(math.sin(2.0 * math.pi * k / RING_SAMPLES) for k in range(RING_SAMPLES))
_QUARTER = RING_SAMPLES // 4


@inline_jit
def _meridian_sample(p, rho, zz, c, s):
    """The meridian of an AXI primitive at azimuth phi from the centre's own (cos c, sin
    s), for a centre at (rho, zz) from the axis: the surface normal there in the meridian
    half-plane (er, ez) and the distance from the centre to its closest point, minus the
    half thickness (the centre lies at (rho c, zz) in that half-plane and rho s out of it).
    """
    er, ez, d = _segment_2d(rho * c, zz, p[6], p[7], p[8], p[9])
    off = rho * s
    return er, ez, math.sqrt(d * d + off * off) - p[10]


@inline_jit
def axi_distance(p, x, y, z, r):
    """Distance and normal of an AXI primitive, with the contact of a sphere of radius r
    that meets the surface in a ring taken as one contact over the ring.

    A sphere whose centre lies on or near the axis (in a cone, over an annulus' hole, on a
    rim) touches the surface along a whole circle, not at one point: the single closest
    point (in the centre's own meridian) would then pick an arbitrary side and push the
    sphere off the axis. When the meridians at 1/16, 1/4 or 1/2 turn from the centre's are
    also within r, the contact is integrated over ``RING_SAMPLES`` meridians at azimuths
    2 pi k / 16: each sample k has overlap d_k = r - dist_k (> 0 counted) and the surface
    normal n_k of its meridian (the pressure direction there), and the contact's normal is
    their overlap-weighted mean N = sum d_k n_k / sum d_k. It is returned unnormalised:
    |N| <= 1 scales the contact's force (the step normalises the direction); dist is that
    of the centre's own meridian (the largest overlap). A symmetric ring gives the mean
    normal of the ring (for a 45 degree cone: cos 45 deg along the axis); a contact that is
    one patch gives |N| = 1 to rounding (every sample normal the same: a face) or nearly (a
    rim it barely wraps); the samples change continuously with the centre, so the force
    does too."""
    dx = x - p[0]
    dy = y - p[1]
    dz = z - p[2]
    ax, ay, az = p[3], p[4], p[5]
    zz = dx * ax + dy * ay + dz * az
    rx = dx - zz * ax
    ry = dy - zz * ay
    rz = dz - zz * az
    rho = math.sqrt(rx * rx + ry * ry + rz * rz)
    if rho > 1e-300:
        inv = 1.0 / rho
        rx *= inv
        ry *= inv
        rz *= inv
    else:
        rx, ry, rz = _unit_perpendicular(ax, ay, az)
    flags = int(p[11])
    # beyond an end joined to the next piece, the contact is that piece's
    feature = JOINED if flags != 0 and ((flags & 1 and zz < p[7]) or
                                        (flags & 2 and zz > p[9])) else 0
    er, ez, d = _segment_2d(rho, zz, p[6], p[7], p[8], p[9])
    dist = d - p[10]
    if dist >= r:
        return (dist, er * rx + ez * ax, er * ry + ez * ay, er * rz + ez * az, feature)
    nx, ny, nz = ring_normal(p, rho, zz, rx, ry, rz, r, er, ez)
    return dist, nx, ny, nz, feature


@jit
def ring_normal(p, rho, zz, rx, ry, rz, r, er, ez):
    """The contact normal of a touching AXI primitive for a centre at (rho, zz) with
    radial unit vector (rx, ry, rz), (er, ez) the normal in the centre's own meridian: that
    normal, unless the meridians 1/16, 1/4 or 1/2 turn away are within r too; then the
    overlap-weighted mean surface normal over ``RING_SAMPLES`` meridians (see
    :func:`axi_distance`). A plain (not inlined) function: every step kernel that inlines
    ``closest`` calls one compiled copy (inlined, it made each scene with a surface of
    revolution compile ~1.6x longer)."""
    ax, ay, az = p[3], p[4], p[5]
    if (_meridian_sample(p, rho, zz, _RING_COS[1], _RING_SIN[1])[2] >= r
            and _meridian_sample(p, rho, zz, _RING_COS[_QUARTER], _RING_SIN[_QUARTER])[2] >= r
            and _meridian_sample(p, rho, zz, -1.0, 0.0)[2] >= r):
        return er * rx + ez * ax, er * ry + ez * ay, er * rz + ez * az
    ex = ay * rz - az * ry  # e = a x (radial): the azimuthal direction
    ey = az * rx - ax * rz
    ez_ = ax * ry - ay * rx
    sr = 0.0
    se = 0.0
    sa = 0.0
    sw = 0.0
    for k in range(RING_SAMPLES):
        c = _RING_COS[k]
        s = _RING_SIN[k]
        er_k, ez_k, d_k = _meridian_sample(p, rho, zz, c, s)
        w = r - d_k
        if w > 0.0:
            sr += w * er_k * c
            se += w * er_k * s
            sa += w * ez_k
            sw += w
    sr /= sw
    se /= sw
    sa /= sw
    return (sr * rx + se * ex + sa * ax, sr * ry + se * ey + sa * ay,
            sr * rz + se * ez_ + sa * az)


@inline_jit
def torus_distance(p, x, y, z):
    dx = x - p[0]
    dy = y - p[1]
    dz = z - p[2]
    ax, ay, az = p[3], p[4], p[5]
    e1x, e1y, e1z = p[6], p[7], p[8]
    e2x = ay * e1z - az * e1y
    e2y = az * e1x - ax * e1z
    e2z = ax * e1y - ay * e1x
    big_r = p[9]
    rp = p[10]
    theta = p[11]
    px = dx * e1x + dy * e1y + dz * e1z
    py = dx * e2x + dy * e2y + dz * e2z
    pz = dx * ax + dy * ay + dz * az
    phi = math.atan2(py, px)
    if phi < 0.0:
        phi += 2.0 * math.pi
    feature = 0
    if phi > theta:  # outside the segment: the nearer end ring
        phi = theta if phi - theta < 2.0 * math.pi - phi else 0.0
        flags = int(p[13])
        if flags != 0 and ((phi == 0.0 and flags & 1) or (phi == theta and flags & 2)):
            feature = JOINED  # beyond an end joined to the next piece
    c = math.cos(phi)
    s = math.sin(phi)
    # pipe centre and tangent at phi, in (e1, e2, a) coordinates
    wx = px - big_r * c
    wy = py - big_r * s
    wz = pz
    tx = -s
    ty = c
    wt = wx * tx + wy * ty
    qx = wx - wt * tx
    qy = wy - wt * ty
    qz = wz
    rho = math.sqrt(qx * qx + qy * qy + qz * qz)
    if rho > 1e-300:
        inv = 1.0 / rho
        qx *= inv
        qy *= inv
        qz *= inv
    else:
        qx, qy, qz = c, s, 0.0
    er = rho - rp
    d = math.sqrt(er * er + wt * wt)
    if d > 0.0:
        er /= d
        et = wt / d
    else:
        er = 1.0
        et = 0.0
    # local normal in (e1, e2, a), then to the boundary frame
    lx = er * qx + et * tx
    ly = er * qy + et * ty
    lz = er * qz
    return (d - p[12], lx * e1x + ly * e2x + lz * ax, lx * e1y + ly * e2y + lz * ay,
            lx * e1z + ly * e2z + lz * az, feature)


@inline_jit
def triangle_closest(p, x, y, z):
    """Closest point (qx, qy, qz) of the triangle p[0:9] to (x, y, z) and its feature."""
    ax, ay, az = p[0], p[1], p[2]
    bx, by, bz = p[3], p[4], p[5]
    cx, cy, cz = p[6], p[7], p[8]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = x - ax, y - ay, z - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, 4
    bpx, bpy, bpz = x - bx, y - by, z - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz, 5
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return ax + v * abx, ay + v * aby, az + v * abz, 1
    cpx, cpy, cpz = x - cx, y - cy, z - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz, 6
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return ax + w * acx, ay + w * acy, az + w * acz, 3
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + w * (cx - bx), by + w * (cy - by), bz + w * (cz - bz), 2
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    return (ax + abx * v + acx * w, ay + aby * v + acy * w, az + abz * v + acz * w, FACE)


@inline_jit
def triangle_distance(p, x, y, z):
    """(dist, nx, ny, nz, feature) of (x, y, z) to the triangle row ``p`` (both sides)."""
    return triangle_distance_within(p, x, y, z, math.inf)


@inline_jit
def triangle_distance_within(p, x, y, z, lim):
    """As :func:`triangle_distance` where the triangle may lie within ``lim``; a triangle
    that certainly lies farther returns (lim, n, FACE) without its closest point.

    The bound: outside the triangle, the in-plane distance to it is at least the largest
    violation of s >= 0, t >= 0, s + t <= 1 times the triangle's smallest altitude
    (p[19]; the distance to the line s = 0 is -s / |g1| and 1 / |g1| is an altitude), so
    the distance is at least sqrt(height^2 + (violation h_min)^2) - half thickness. Most
    candidates of a sphere resting on a mesh are its touching triangle's neighbours: each
    skips Ericson's branches. A row without p[19] (zero) keeps the height alone as its
    bound (the triangle's plane farther than ``lim``)."""
    px = x - p[0]
    py = y - p[1]
    pz = z - p[2]
    s = px * p[13] + py * p[14] + pz * p[15]
    t = px * p[16] + py * p[17] + pz * p[18]
    fnx, fny, fnz = p[10], p[11], p[12]
    hgt = px * fnx + py * fny + pz * fnz
    if s > 0.0 and t > 0.0 and s + t < 1.0:  # over the inside: a face contact
        if hgt < 0.0:
            return -hgt - p[9], -fnx, -fny, -fnz, FACE
        return hgt - p[9], fnx, fny, fnz, FACE
    e = max(-s, -t, s + t - 1.0) * p[19]
    m = lim + p[9]
    if hgt * hgt + e * e > m * m * (1.0 + 1e-9):
        return lim, fnx, fny, fnz, FACE
    qx, qy, qz, feature = triangle_closest(p, x, y, z)
    ex = x - qx
    ey = y - qy
    ez = z - qz
    d = math.sqrt(ex * ex + ey * ey + ez * ez)
    if d > 0.0:
        inv = 1.0 / d
        ex *= inv
        ey *= inv
        ez *= inv
        # a closest point on an edge or vertex whose direction is the face normal lies on
        # the face's rim: it is a face contact, with the face's normal and plane distance
        # (the coplanar neighbour then gives identical geometry)
        dot = ex * fnx + ey * fny + ez * fnz
        if feature != FACE and abs(dot) > 1.0 - 1e-12:
            sg = 1.0 if dot > 0.0 else -1.0
            return d * abs(dot) - p[9], sg * fnx, sg * fny, sg * fnz, FACE
        return d - p[9], ex, ey, ez, feature
    return -p[9], fnx, fny, fnz, FACE


@inline_jit
def sieve_distance(p, x, y, z, r):
    """Distance to a sieve plate of a clearance model (see the module docstring); ``r`` the
    sphere radius (used by the radius-dependent model)."""
    s, t, w, ux, uy, uz, vx, vy, vz, wx, wy, wz = plate_coordinates(p, x, y, z)
    a = p[9]
    b = p[10]
    h = p[11]
    wh = p[12]
    pitch = p[13]
    shape = int(p[14])
    model = int(p[15])
    # beyond the plate's outline: a rounded slab edge
    if abs(s) > a or abs(t) > b:
        return slab_distance(p, x, y, z)
    # position relative to the centre of the pitch cell's hole
    hs = s - pitch * math.floor(s / pitch + 0.5)
    ht = t - pitch * math.floor(t / pitch + 0.5)
    sg = 1.0 if w >= 0.0 else -1.0
    half = 0.5 * wh
    if r < half:
        clear = p[16] * (half - r) if model == 1 else p[16] * half
        reduced = half - clear
        if shape == 1:
            rho = math.sqrt(hs * hs + ht * ht)
            inside = rho < reduced
            in_hole = rho < half
            g = half - rho  # in-plane gap to the rim, towards the hole's centre:
            if rho > 0.0:
                gs = -hs / rho
                gt = -ht / rho
            else:
                gs = 1.0
                gt = 0.0
        else:
            inside = abs(hs) < reduced and abs(ht) < reduced
            in_hole = abs(hs) < half and abs(ht) < half
            g = half - max(abs(hs), abs(ht))
            if abs(hs) >= abs(ht):
                gs = -1.0 if hs >= 0.0 else 1.0
                gt = 0.0
            else:
                gs = 0.0
                gt = -1.0 if ht >= 0.0 else 1.0
        we = max(abs(w) - h, 0.0)
        if in_hole and (inside or we < 0.75 * r):
            # passing, or already inside the hole: the rim of the real hole
            d = math.sqrt(g * g + we * we)
            if d > 0.0:
                cs = g / d
                cw = we / d
            else:
                cs = 1.0
                cw = 0.0
            return (d, cs * (gs * ux + gt * vx) + cw * sg * wx,
                    cs * (gs * uy + gt * vy) + cw * sg * wy,
                    cs * (gs * uz + gt * vz) + cw * sg * wz)
    return abs(w) - h, sg * wx, sg * wy, sg * wz


@jit
def closest_any(kind, p, x, y, z, r):
    """(dist, nx, ny, nz, feature) of a sphere of radius r centred at (x, y, z), for any
    built-in kind (tests, tools, the inlets' placement test; the step compiles a ``closest``
    of the scene's kinds, plugin kinds included: dpm.boundaries.primitives). Another kind
    counts as absent: distance inf."""
    if kind == PLANE:
        d, nx, ny, nz = plane_distance(p, x, y, z)
        return d, nx, ny, nz, 0
    if kind == SLAB:
        d, nx, ny, nz = slab_distance(p, x, y, z)
        return d, nx, ny, nz, 0
    if kind == AXI:
        return axi_distance(p, x, y, z, r)
    if kind == TORUS:
        return torus_distance(p, x, y, z)
    if kind == TRIANGLE:
        return triangle_distance(p, x, y, z)
    if kind == SIEVE:
        d, nx, ny, nz = sieve_distance(p, x, y, z, r)
        return d, nx, ny, nz, 0
    return math.inf, 0.0, 0.0, 1.0, 0


@inline_jit
def off_triangle_plane(par, w, x, y, z, reach):
    """Whether (x, y, z) lies more than ``reach`` from the plane of the triangle in row w
    of ``par`` (its half thickness par[w, 9] taken off): then the triangle itself lies
    farther than that too. Three products instead of a closest point: the boundary
    search's cheap reject of the candidates a mesh grid's cell yields (a large triangle
    sits in many cells). Indexed in place: a row view per candidate was a large share
    of the search. The margin keeps the reject strictly inside what ``in_range`` would
    refuse."""
    h = ((x - par[w, 0]) * par[w, 10] + (y - par[w, 1]) * par[w, 11]
         + (z - par[w, 2]) * par[w, 12])
    return abs(h) - par[w, 9] > reach * (1.0 + 1e-9)


@inline_jit
def in_range(kind, dist, r, reach):
    """Whether a primitive at ``dist`` belongs in the wall list of a sphere of radius r:
    within r + reach in front (planes: and not more than r + reach behind)."""
    if kind == PLANE:
        return -r - reach < dist < r + reach
    return dist < r + reach


@inline_jit
def touching(kind, dist, r):
    """Whether a sphere of radius r at ``dist`` overlaps the primitive."""
    if kind == PLANE:
        return -r < dist < r
    return dist < r
