"""Path-traced material presets (`vrneural btf render`): microgeometry a heightfield or a lobe
cannot express. Each is ``(rng) -> Tile`` in tile units (the tile is the unit square; heights in
tile widths); all randomness comes from ``rng``, so a seed fixes the material.

- ``weave``:   plain-weave fabric, each yarn a bundle of twisted fibre cylinders (overhangs,
  see-through gaps onto a dark backing, anisotropic glossy fibres);
- ``pebbles``: packed pebbles of bright and dark stone, some wet and glossy, on sand (deep gaps,
  strong interreflection between bright stones);
- ``fur``:     cut pile of thin curved strands on a backing (fibre-scale masking and
  shadowing, light scattered deep into the pile);
- ``bark``:    a fissured bark of fibrous plates and deep narrow crevices, lichen on the
  plates (a textured blend of two BSDFs), glossy sap in the cracks' walls;
- ``mosaic``:  tall tesserae of polished and brushed metals and glossy plastics, each tilted
  and bevelled, in deep sanded grout (mirror-like highlights that jump from tile to tile,
  walls that hide and shadow the grout, grains that slide under a texel with the view);
- ``berber``:  multi-level loop-pile carpet, each loop a bundle of twisted glossy fibres
  leaning out over its feet (overhangs; high loops hide and shadow low ones; flecked yarn
  that slides under a texel with the view).

Values stay physically plausible: diffuse albedo <= 0.85, dielectrics with IOR 1.5, metals
from Mitsuba's measured conductor data.
"""

from __future__ import annotations

import numpy as np

from vrneural.btf.heightfield import smoothstep, spectral_noise, toroidal_cells
from vrneural.btf.pt_geometry import Part, Tile, blob, heightfield, merge, slab, tube


def _rgb(c) -> dict:
    return {"type": "rgb", "value": [float(x) for x in c]}


def _at(field: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """A periodic field ``[N, N]`` at points ``xy [K, 2]`` of the unit tile (nearest cell)."""
    ij = (xy * len(field)).astype(int) % len(field)
    return field[ij[:, 1], ij[:, 0]]


def plastic(colour, alpha: float) -> dict:
    """A rough dielectric coating over a diffuse base (Mitsuba ``roughplastic``, GGX)."""
    return {
        "type": "roughplastic",
        "distribution": "ggx",
        "alpha": float(alpha),
        "diffuse_reflectance": _rgb(colour),
        "int_ior": 1.5,
    }


def diffuse(colour) -> dict:
    return {
        "type": "diffuse",
        "reflectance": _rgb(colour) if not isinstance(colour, dict) else colour,
    }


def metal(material: str, alpha_u: float, alpha_v: float | None = None) -> dict:
    """A rough conductor (GGX; ``alpha_u`` along the mesh's u, ``alpha_v`` across)."""
    d = {"type": "roughconductor", "material": material, "distribution": "ggx"}
    if alpha_v is None or alpha_v == alpha_u:
        return {**d, "alpha": float(alpha_u)}
    return {**d, "alpha_u": float(alpha_u), "alpha_v": float(alpha_v)}


#: the weave's yarn colours (linear RGB): two blues along y (warp), two tans along x (weft)
WEAVE_COLOURS = {
    "warp_a": (0.04, 0.08, 0.32),
    "warp_b": (0.05, 0.12, 0.40),
    "weft_a": (0.62, 0.50, 0.30),
    "weft_b": (0.70, 0.58, 0.36),
}


def weave(
    rng, threads: int = 4, fibres: int = 5, gloss: float = 0.22, colours: dict | None = None
) -> Tile:
    """Plain weave: ``threads`` warp yarns (along y) and weft yarns (along x) per tile, each a
    bundle of ``fibres`` fibre cylinders twisted around the yarn's centreline, going over and
    under each other; gaps between the yarns show a dark backing. The fibres are a rough
    plastic of GGX ``gloss`` (alpha) in :data:`WEAVE_COLOURS`, or ``colours`` (any of its keys
    replaced)."""
    pitch = 1.0 / threads
    R = 0.32 * pitch  # yarn radius: gaps of about a third of the pitch
    A = 0.95 * R  # undulation amplitude: crossing yarns just touch
    rf = 0.42 * R  # fibre radius
    k = 32 * threads + 1
    s = np.linspace(0.0, 1.0, k)
    twist = 3 * threads  # whole turns per tile: periodic
    parts: dict[str, list] = {"warp_a": [], "warp_b": [], "weft_a": [], "weft_b": []}
    for j in range(threads):
        for kind in ("warp", "weft"):
            c = (j + 0.5) * pitch
            sign = 1.0 if kind == "warp" else -1.0
            z = sign * A * np.cos(np.pi * (threads * s - 0.5 - j))
            phase0 = rng.uniform(0, 2 * np.pi)
            for f in range(fibres):
                ang = 2 * np.pi * (twist * s + f / fibres) + phase0
                off = (R - rf) * (1.0 + 0.08 * rng.standard_normal())
                a, b = c + off * np.cos(ang), z + off * np.sin(ang)
                path = np.column_stack([a, s, b] if kind == "warp" else [s, a, b])
                ref = [1.0, 0.0, 0.0] if kind == "warp" else [0.0, 1.0, 0.0]
                m = tube(path, rf * (1.0 + 0.1 * rng.standard_normal()), sides=8, ref=ref)
                parts[f"{kind}_{'ab'[j % 2]}"].append(m)
    cols = WEAVE_COLOURS | (colours or {})
    out = [Part(merge(ms), plastic(cols[name], gloss), name=name) for name, ms in parts.items()]
    back = heightfield(np.full((4, 4), -A - 1.6 * R))
    out.append(Part(back, diffuse((0.03, 0.03, 0.035)), name="backing"))
    return Tile(out, f"plain weave, {threads} yarns of {fibres} twisted fibres per tile")


def _pack(rng, count: int, rmin: float, rmax: float, tries: int = 4000):
    """Up to ``count`` discs on the unit torus, radii in ``[rmin, rmax]``, largest first,
    not overlapping (toroidal distances). Returns ``[(x, y, r)]``."""
    out: list[tuple[float, float, float]] = []
    radii = np.sort(rng.uniform(rmin, rmax, count))[::-1]
    for r in radii:
        for _ in range(tries // count):
            x, y = rng.random(2)
            ok = True
            for px, py, pr in out:
                dx, dy = abs(x - px), abs(y - py)
                if np.hypot(min(dx, 1 - dx), min(dy, 1 - dy)) < 0.95 * (r + pr):
                    ok = False
                    break
            if ok:
                out.append((float(x), float(y), float(r)))
                break
    return out


def pebbles(rng, count: int = 34) -> Tile:
    """Packed pebbles (ellipsoids with bumps) of six kinds of stone, some wet and glossy,
    bedded in bright sand: deep gaps, interreflection between the bright stones. Up to
    ``count`` are tried; as many as fit without overlapping are placed (22 with seed 0)."""
    kinds = [
        plastic((0.80, 0.76, 0.68), 0.35),  # pale limestone, slightly polished
        diffuse((0.85, 0.83, 0.80)),  # white quartz
        diffuse((0.55, 0.30, 0.18)),  # red sandstone
        plastic((0.08, 0.08, 0.09), 0.06),  # wet black basalt: a sharp highlight
        plastic((0.35, 0.40, 0.30), 0.12),  # green serpentine, glossy
        diffuse((0.45, 0.44, 0.42)),  # grey granite
    ]
    groups: list[list] = [[] for _ in kinds]
    placed = _pack(rng, count, 0.06, 0.13)  # as many as fit without overlapping
    for x, y, r in placed:
        rz = r * rng.uniform(0.55, 0.85)
        kind = int(rng.choice(len(kinds), p=[0.25, 0.15, 0.2, 0.1, 0.1, 0.2]))
        level = 3 if r > 0.09 else 2
        m = blob(rng, (x, y, rz * 0.55), (r, r * rng.uniform(0.7, 1.0), rz), level, bumps=0.12)
        groups[kind].append(m)
    parts = [Part(merge(g), kinds[k], name=f"stone{k}") for k, g in enumerate(groups) if g]
    sand = 0.004 * spectral_noise(rng, 64, 4, 24, beta=1.5)
    parts.append(Part(heightfield(sand), diffuse((0.70, 0.62, 0.48)), name="sand"))
    return Tile(parts, f"{len(placed)} packed pebbles of six stones on sand")


def fur(
    rng,
    tufts: int = 144,
    per_tuft: int = 80,
    gloss: float = 0.12,
    lean: float = 0.15,
    heights: tuple[float, float] = (0.14, 0.17),
    radius: float = 0.002,
    crimp: float = 0.0,
    bundle: float = 0.0,
    twist: float = 1.5,
    carve: float = 0.0,
    carved: float = 0.5,
    bands: tuple[float, float] = (0.5, 0.5),
) -> Tile:
    """Clipped cut pile: ``tufts`` tufts (on a jittered grid) of ``per_tuft`` thin tapered
    strands each, standing on a backing, leaning (each tuft by a slope of standard deviation
    ``lean``) and curling. The tufts' yarn colour follows patches of a few tufts: a patch
    field (2-6 cycles a tile) cut at its quantiles ``bands`` into cream, russet and
    near-black (the default ``(0.5, 0.5)`` leaves no russet: cream and near-black spots, half
    each, a pelt's). The pile is clipped to nearly one height (each tuft ``heights``, tile
    widths, 0.14-0.17): its tips are one surface about 10 texels above the backing, whose
    spots slide coherently under a texel as the view tilts (9 texels at 45 degrees, 35 at 74)
    while the strands' sides hide and shadow what is behind them. Strands are very fine
    (``radius`` 0.002 tile widths at the root, an eighth of a texel at 64^2, 80 a tuft): a
    texel sees many, as a camera sees velvet or fur, not one strand that changes from view to
    view. The strands' coating is glossy (GGX alpha ``gloss``), as a hair's cuticle: each
    strand a narrow highlight along its own axis. ``crimp`` (wavy strands) and
    ``bundle``/``twist`` (each tuft a twisted yarn, a saxony carpet) are the variants' knobs,
    off by default, as is ``carve``: the share of tufts nearest the patches' borders cut down
    to ``carved`` of their height (a carved rug's channels outlining its pattern).

    The seventh version (Lafortune / NeuMIP with offset 1.56 over five seeds, 1.48-1.66 by
    seed). The sixth had three colours (shares 40/30/30) and 40 strands a tuft twice as thick
    (1.36 over five seeds); two colours alone gave 1.49 over five seeds, the finer strands
    alone 1.38 (seed 0); a taller, denser or carved pile, or glossier strands, 1.30-1.37 (seed
    0). The fifth
    had tufts of varied height (0.07-0.19: 1.25 over five seeds); a pile clipped lower
    (0.09-0.11) gave 1.27 (seed 0), shinier and lower strands 1.18, crimped thick strands 1.17,
    saxony tufts 1.07. The fourth had a rough coating (alpha 0.35: 1.19 over five seeds);
    glossy tufts that also lean more fell back to 1.19 (seed 0). The third had patches at 1-3
    cycles a tile (1.16); at 4-10 cycles it fell back to 1.15, and tipped strands gave 1.12.
    The second had 14 strands a tuft of radius 0.009: 1.12 there, 1.16 with the finer strands;
    a combed nap made it 1.08. On the first (100 tufts of three reds and greys chosen per tuft,
    all 0.11-0.16 tall) the lobes beat NeuMIP with parallax (0.93). A short pile (0.035-0.075)
    and finer patches made the lobes win again (0.92): docs/quality-research.md."""
    k = round(np.sqrt(tufts))
    base = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.5) / k
    centres = (base + (rng.random(base.shape) - 0.5) * 0.6 / k) % 1.0
    cols = [(0.80, 0.72, 0.58), (0.60, 0.24, 0.06), (0.07, 0.05, 0.04)]
    # patches: a coarse periodic field looked up at each tuft's centre, cut at ``bands``
    field = spectral_noise(rng, 64, 2, 6, beta=2.0)
    at = _at(field, centres)
    colour = np.digitize(at, np.quantile(at, bands))
    tall = rng.uniform(*heights, len(centres))
    if carve:  # the tufts nearest a band's edge (in the field's rank) cut down: the channels
        rank = np.argsort(np.argsort(at)) / (len(at) - 1)
        edge = np.min(np.abs(rank[:, None] - np.array(bands)), axis=1)
        tall = np.where(edge <= np.quantile(edge, carve), tall * carved, tall)
    groups: list[list] = [[] for _ in cols]
    t = np.linspace(0.0, 1.0, 19 if crimp or bundle else 7)
    for (cx, cy), c, top in zip(centres, colour, tall, strict=True):
        tuft_lean = rng.normal(0, lean, 2)
        axis = np.array([cx, cy]) + np.outer(t, tuft_lean * top) if bundle else None
        for _ in range(per_tuft):
            if bundle:  # a twisted yarn cut off (saxony): strands wound around the tuft's axis
                ang = rng.uniform(0, 2 * np.pi) + 2 * np.pi * twist * t
                rr = bundle * np.sqrt(rng.uniform(0.15, 1.0))
                h = top * rng.uniform(0.92, 1.0)
                xy, taper = axis + rr * np.column_stack([np.cos(ang), np.sin(ang)]), 0.5
            else:
                p0 = np.array([cx, cy]) + rng.normal(0, 0.022, 2)
                h = top * rng.uniform(0.85, 1.0)
                tilt = tuft_lean + rng.normal(0, 0.12, 2)
                curl = rng.normal(0, 0.02, 2)
                xy, taper = p0 + np.outer(t, tilt * h) + np.outer(t**2, curl), 0.7
            if crimp:  # a wavy strand (wool's crimp): 2-3 waves, a random plane and phase
                a, w, ph = rng.uniform(0, 2 * np.pi), rng.uniform(2.0, 3.0), rng.uniform(0, 6.3)
                wave = crimp * np.sqrt(t) * np.sin(2 * np.pi * w * t + ph)
                xy = xy + np.outer(wave, [np.cos(a), np.sin(a)])
            path = np.column_stack([xy, h * t])
            r = radius * (1.0 - taper * t)
            groups[int(c)].append(tube(path, r, sides=5, ref=[1.0, 0.0, 0.0]))
    parts = [
        Part(merge(g), plastic(cols[i], gloss), name=f"yarn{i}") for i, g in enumerate(groups) if g
    ]
    back = heightfield(0.002 * spectral_noise(rng, 32, 2, 12))
    parts.append(Part(back, diffuse((0.20, 0.16, 0.11)), name="backing"))
    coat = "calico" if bands[0] < bands[1] else "spotted"
    return Tile(parts, f"{coat} cut pile, {k * k} tufts of {per_tuft} strands")


def bark(rng, n: int = 160) -> Tile:
    """Fissured bark: plates of varied tone, elongated along y, between deep crevices (about
    a fifth of the tile deep, a third of its area); the plates' surface split into fibres along
    y (streaks of 4-13 texels at 64^2, pale and dark, each a shallow ridge); lichen patches on
    the plates (a texture blending two BSDFs); darker, glossier crevice walls.

    The second version. On the first (crevices on a fifth of the area, each plate's colour
    uniform but for the lichen) the lobes came within 22% of NeuMIP with parallax at 64^2: a
    uniform plate looks the same wherever the view lands on it. Streaked plates, further
    above the reference plane (wider crevices lower it), show another streak under a texel at
    each view: what a lobe cannot follow and a height field can (docs/quality-research.md)."""
    f1, f2, ids = toroidal_cells(rng, n, 40, jitter=0.9)
    # stretch the cells along y: distance field of a squashed copy of the grid
    ridge = spectral_noise(rng, n, 1, 10, beta=2.5, stretch=(1.0, 5.0))
    gap = f2 - f1
    crevice = 1.0 - smoothstep(0.0, 0.045, gap + 0.01 * ridge)
    plates = 0.012 * spectral_noise(rng, n, 2, 30, beta=2.0)
    fibres = spectral_noise(rng, n, 5, 16, beta=1.0, stretch=(1.0, 6.0))  # streaks along y
    height = (
        0.08 * (1.0 - crevice) ** 0.5 + plates + 0.006 * fibres * (1 - crevice) - 0.12 * crevice
    )
    tone = rng.uniform(0.45, 1.25, ids.max() + 1)[ids] * (1.0 + 0.7 * np.tanh(fibres))
    lichen = smoothstep(0.6, 1.2, spectral_noise(rng, n, 3, 20, beta=2.0)) * (1 - crevice)
    albedo = np.stack([0.30 * tone, 0.22 * tone, 0.15 * tone], -1) * (
        1.0 - 0.7 * crevice[..., None]
    )
    albedo = albedo * (1 - lichen[..., None]) + lichen[..., None] * np.array([0.55, 0.62, 0.40])
    bark_bsdf = {
        "type": "blendbsdf",
        "weight": {"type": "bitmap", "data": crevice[..., None].astype(np.float32)},
        "bsdf_0": {
            "type": "diffuse",
            "reflectance": {"type": "bitmap", "data": albedo.astype(np.float32)},
        },
        "bsdf_1": plastic((0.06, 0.04, 0.03), 0.15),
    }
    return Tile(
        [Part(heightfield(height), bark_bsdf, name="bark")], "fissured fibrous bark with lichen"
    )


def berber(
    rng,
    rows: int = 10,
    loops: int = 6,
    fibres: int = 5,
    gloss: float = 0.04,
    heights: tuple[float, float] = (0.04, 0.12),
    flecks: tuple[float, float] = (3.0, 8.0),
    shares: tuple[float, float, float] = (0.45, 0.7, 0.88),
    yarn: float = 0.3,
    backing: tuple[float, float, float] = (0.05, 0.045, 0.04),
) -> Tile:
    """Loop-pile (Berber) carpet: ``rows`` tufting rows per tile (along y), each a yarn that
    rises into ``loops`` loops per tile and dives into the backing between them; rows offset
    by half a loop. Each loop is more than a half circle (its sides lean out over its feet:
    overhangs) stretched upward, and its yarn a bundle of ``fibres`` fibre cylinders twisted
    around the centreline: a shiny synthetic yarn (GGX alpha ``gloss``), each fibre's
    highlight a narrow cone around its axis. Multi-level: the loops' heights (``heights``, tile
    widths) follow a coarse pattern, so high loops hide and shadow the low ones beside them at
    grazing views; the yarn is flecked (oatmeal, cream, brown, charcoal; the colour changes
    from loop to loop in patches of a few loops: ``flecks`` is the colour field's band in
    cycles per tile, ``shares`` its quantile cuts between the four colours); dark gaps between
    the rows (yarn radius ``yarn`` row pitches, backing albedo ``backing``) show at
    near-normal views and close at grazing ones. Structure of a few texels that casts hard
    shadows, hides itself and slides under a texel with the view (as on the weave), on a pile:
    what a lobe per texel cannot follow. The defaults are the ninth version (v9) (alpha 0.04 and
    loops 0.04-0.12; the first had 0.2 and 0.05-0.17); the other knobs are the variants'
    (docs/quality-research.md)."""
    pitch_x, pitch_y = 1.0 / rows, 1.0 / loops
    R = yarn * pitch_x  # yarn radius (about 2 texels at 64^2)
    rf = 0.45 * R  # fibre radius
    cols = [(0.72, 0.64, 0.50), (0.82, 0.78, 0.68), (0.42, 0.27, 0.15), (0.09, 0.08, 0.07)]
    # multi-level pattern: a coarse periodic field at the loops' tops; fleck patches: a finer one
    level = spectral_noise(rng, 64, 1, 3, beta=2.0)
    fleck = spectral_noise(rng, 64, *flecks, beta=1.0)
    pos = [
        ((i + 0.5) * pitch_x, (j + 0.5 * (i % 2)) * pitch_y)
        for i in range(rows)
        for j in range(loops)
    ]
    pos = np.array(pos) % 1.0
    lv, fl = _at(level, pos), _at(fleck, pos)
    rank = np.argsort(np.argsort(lv)) / (len(pos) - 1)
    tall = heights[0] + (heights[1] - heights[0]) * rank
    colour = np.digitize(fl, np.quantile(fl, shares))
    groups: list[list] = [[] for _ in cols]
    over = np.radians(25.0)  # how far past a half circle each loop goes (its overhang)
    phi = np.linspace(-over, np.pi + over, 25)
    s = np.linspace(0.0, 1.0, len(phi))  # along the loop, for the fibres' twist
    r = 0.35 * pitch_y  # loop half-width at its widest
    for (cx, cy), top, c in zip(pos, tall, colour, strict=True):
        stretch = top / (r * (1.0 + np.sin(over)))
        ys = cy - r * np.cos(phi)
        zs = stretch * r * (np.sin(phi) + np.sin(over)) - 0.5 * R
        xs = cx + rng.normal(0, 0.08 * pitch_x) + 0.15 * R * np.sin(phi)
        centre = np.column_stack([xs, ys, zs])
        t = np.gradient(centre, axis=0)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        n1 = np.cross(t, [1.0, 0.0, 0.0])
        n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
        n2 = np.cross(t, n1)
        phase0 = rng.uniform(0, 2 * np.pi)
        for f in range(fibres):
            ang = 2 * np.pi * (1.5 * s + f / fibres) + phase0
            off = (R - rf) * (1.0 + 0.08 * rng.standard_normal())
            path = centre + off * (np.cos(ang)[:, None] * n1 + np.sin(ang)[:, None] * n2)
            m = tube(path, rf * (1.0 + 0.1 * rng.standard_normal()), sides=6, ref=[1.0, 0.0, 0.0])
            groups[int(c)].append(m)
    parts = [
        Part(merge(g), plastic(cols[i], gloss), name=f"yarn{i}") for i, g in enumerate(groups) if g
    ]
    back = heightfield(-0.5 * R + 0.002 * spectral_noise(rng, 32, 2, 12))
    parts.append(Part(back, diffuse(backing), name="backing"))
    return Tile(parts, f"multi-level loop pile, {rows} rows of {loops} loops of {fibres} fibres")


#: the grout's colour (scaled per grain)
GROUT = np.array([1.0, 0.96, 0.9])


def mosaic(rng, cells: int = 8) -> Tile:
    """A ``cells x cells`` mosaic of tall tesserae: polished and brushed metals (copper, gold,
    aluminium, chromium) and glossy coloured plastics, each with jittered corners, a random
    tilt of up to 10 degrees and a bevel, standing 0.045-0.07 tile widths above deep, sanded
    grout (pale and dark grains).

    The third version. On the first (5 x 5 tesserae, 0.024-0.032 above shallow grout) the
    lobes came within 16% of NeuMIP with parallax at 64^2: a texel on a flat tessera has one
    lobe, which is what Lafortune fits. The second has smaller tesserae (more edge texels)
    and taller ones (side walls seen at grazing views, grout shadowed by the walls; relief
    4.7 texels at 64^2, was 2.4): angular functions with occlusion steps, but the lobes still
    came within 32%, and height parallax helped NeuMIP by 2% only, because uniform grey grout
    looks the same wherever the view lands on it. The grains of this one, 0.045-0.07 tile widths
    below the tesserae's tops, slide under a texel as the view tilts: what a lobe cannot
    follow and a height field can (docs/quality-research.md)."""
    pitch = 1.0 / cells
    mats = [
        lambda: metal("Cu", rng.uniform(0.05, 0.2)),
        lambda: metal("Au", rng.uniform(0.03, 0.15)),
        lambda: metal("Al", 0.04, rng.uniform(0.25, 0.4)),  # brushed along u
        lambda: metal("Cr", rng.uniform(0.02, 0.1)),
        lambda: plastic(rng.uniform(0.05, 0.6, 3), rng.uniform(0.02, 0.12)),
        lambda: plastic(rng.uniform(0.05, 0.6, 3), rng.uniform(0.02, 0.12)),
    ]
    parts = []
    for i in range(cells):
        for j in range(cells):
            lo = np.array([j, i]) * pitch + 0.09 * pitch
            hi = lo + 0.82 * pitch
            corners = np.array([lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]])
            corners += rng.normal(0, 0.03 * pitch, corners.shape)
            tilt = np.tan(np.radians(rng.uniform(0, 10))) * np.array(
                [np.cos(a := rng.uniform(0, 2 * np.pi)), np.sin(a)]
            )
            m = slab(corners, -0.04, (rng.uniform(0.015, 0.04), *tilt), bevel=0.08 * pitch)
            bsdf = mats[int(rng.integers(len(mats)))]()
            parts.append(Part(m, bsdf, smooth=False, name=f"tessera{i}_{j}"))
    grout = heightfield(-0.03 + 0.002 * spectral_noise(rng, 64, 4, 32, beta=1.0))
    # sanded grout: pale and dark grains of 1.5-5 texels at 64^2 (albedo 0.15-0.85)
    grains = 0.5 + 0.35 * np.tanh(1.5 * spectral_noise(rng, 160, 12, 40, beta=0.5))
    sand = {"type": "bitmap", "data": (grains[..., None] * GROUT).astype(np.float32)}
    parts.append(Part(grout, diffuse(sand), name="grout"))
    return Tile(parts, f"{cells}x{cells} mosaic of tall metal and plastic tesserae, sanded grout")


PT_PRESETS = {
    "weave": weave,
    "pebbles": pebbles,
    "fur": fur,
    "bark": bark,
    "mosaic": mosaic,
    "berber": berber,
}
