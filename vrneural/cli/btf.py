"""`vrneural btf`: synthesize, inspect, show and import tabulated BTFs.

    vrneural btf synth --preset leather --res 64 --dirs 151 --seed 0 -o leather.btf [--force]
    vrneural btf render weave --res 64 --dirs 24 --spp 64 -o weave.btf [--force] [--resume]
    vrneural btf info FILE [--json]
    vrneural btf show FILE -o sheet.png [--texel X Y] [--force]
    vrneural btf show A.btf B.btf ... -o gallery.png [--force]
    vrneural btf import UBO.btf -o out.btf [--force] [--resume]

Every input is validated before any output is touched; an existing output is never replaced
without ``--force``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from vrneural.btf.config import PRESET_NAMES, PT_PRESET_NAMES, BtfConfig, RenderConfig
from vrneural.config import add_config_args, config_from_args, config_path, write_config
from vrneural.errors import VrnError, check_range
from vrneural.outputs import (
    check_output,
    check_outputs,
    check_resume_force,
    check_suffix,
    output_lock,
    partial_path,
)


def register(sub) -> None:
    p = sub.add_parser(
        "btf",
        help="synthesize, inspect, show and import tabulated BTFs",
        description="Tabulated BTFs (values[light, view, y, x, rgb], float16): synthetic "
        "presets, UBO2014 import, summaries and contact sheets.",
    )
    bsub = p.add_subparsers(dest="btf_command", required=True, metavar="SUBCOMMAND")

    s = bsub.add_parser(
        "synth",
        help="render a synthetic preset into a .btf (streaming, resumable)",
        description="Render a procedural heightfield material (presets: "
        f"{', '.join(PRESET_NAMES)}) into a .btf file, one view at a time.",
    )
    add_config_args(s, BtfConfig)
    s.add_argument("-o", "--output", required=True, help="output .btf file")
    _run_flags(s, run_synth)

    r = bsub.add_parser(
        "render",
        help="path-trace a microgeometry preset with Mitsuba 3 into a .btf (resumable)",
        description="Path-trace a preset's microgeometry (triangle meshes surrounded by copies "
        "of the tile, Mitsuba's own BSDFs, multiple bounces) into a .btf file, one view at a "
        f"time; rectified slices, cos(theta_i) inside. Presets: {', '.join(PT_PRESET_NAMES)}. "
        "Needs the render extra: pip install 'vrneural[render]'.",
    )
    r.add_argument("preset", help=f"the preset to render ({', '.join(PT_PRESET_NAMES)})")
    add_config_args(r, RenderConfig, skip=("preset",))
    r.add_argument("-o", "--output", required=True, help="output .btf file")
    _run_flags(r, run_render)

    i = bsub.add_parser(
        "info",
        help="shape, directions, value range, size and metadata",
        description="Shape, directions, value range, size and metadata.",
    )
    i.add_argument("file", help="a .btf file")
    i.add_argument("--json", action="store_true", help="print machine-readable JSON")
    i.set_defaults(func=run_info)

    sh = bsub.add_parser(
        "show",
        help="write a contact sheet PNG (several files: a gallery side by side)",
        description="write a contact sheet PNG: slices at characteristic (wi, wo) pairs, each "
        "panel titled with the pair asked for and the nearest slice the BTF has (angles, "
        "indices), plus one texel's unfolded BRDF. With several files, a gallery: one row "
        "per file, one column per pair, to compare materials.",
    )
    sh.add_argument("file", nargs="+", help="a .btf file (several: a gallery)")
    sh.add_argument("-o", "--output", required=True, help="output .png")
    sh.add_argument(
        "--texel",
        type=int,
        nargs=2,
        metavar=("X", "Y"),
        help="texel whose unfolded BRDF is shown (default: the centre)",
    )
    sh.add_argument("--force", action="store_true", help="overwrite an existing output")
    sh.set_defaults(func=run_show)

    im = bsub.add_parser(
        "import",
        help="convert a UBO2014 .btf (needs btf-extractor) or a folder of images",
        description="Convert a UBO2014 .btf file (needs btf-extractor), or a folder of images "
        "(EXR/HDR/PNG/TIFF/PFM, one per (light, view) pair) with a direction table "
        "(directions.csv or directions.json: file, theta_i, phi_i, theta_v, phi_v in degrees, "
        "or file, wi_x, wi_y, wi_z, wo_x, wo_y, wo_z unit vectors). 8/16-bit images are "
        "taken as sRGB and linearised.",
    )
    im.add_argument("file", help="a UBO2014 .btf file, or a folder of images")
    im.add_argument("-o", "--output", required=True, help="output .btf file (our format)")
    im.add_argument(
        "--table",
        help="image sets: the direction table (default: directions.csv or directions.json "
        "in the folder)",
    )
    im.add_argument(
        "--png-linear",
        action="store_true",
        help="image sets: 8/16-bit images hold linear values (default: sRGB, linearised)",
    )
    im.add_argument(
        "--height",
        help="the tile's measured height field, carried into the BTF for parallax: a .npy "
        "[N, N] or a one-channel image (EXR/PFM/TIFF/PNG), square like the texels",
    )
    im.add_argument(
        "--height-scale",
        type=float,
        default=1.0,
        help="multiplies --height's values into UV units (tile widths; for millimetres on a "
        "tile w mm wide: 1/w); the mean is removed",
    )
    _run_flags(im, run_import, "continue an interrupted import")


def _run_flags(p, func, resume_help="continue an interrupted run (<output>.partial)") -> None:
    """--force, --resume and --no-progress of the subcommands that write a .btf, and ``func``."""
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.add_argument("--resume", action="store_true", help=resume_help)
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=func)


def _check_partial(out: Path, resume: bool, force: bool) -> None:
    """An interrupted run's ``<out>.partial`` is only continued (--resume) or discarded (--force)
    on request: a long render is never thrown away by accident."""
    partial = partial_path(out)
    if partial.exists() and not (resume or force):
        raise VrnError(
            f"{partial} exists from an interrupted run; pass --resume to continue it "
            "or --force to start over"
        )
    if resume and not force and not partial.exists():
        raise VrnError(f"--resume: nothing to resume, {partial} does not exist; drop --resume")


def _check_finished(output: str, resume: bool) -> None:
    """--resume on an output that a finished run wrote (no ``.partial`` beside it) is answered
    as what it is, not as an output that --force would overwrite."""
    out = Path(output)
    if resume and out.exists() and not partial_path(out).exists():
        raise VrnError(
            f"--resume: {out} is already complete (no {out.name}.partial beside it), nothing to "
            "resume; pass --force instead of --resume to make it again"
        )


def run_synth(args) -> int:
    from vrneural.btf.synth import synthesize

    cfg = config_from_args(BtfConfig, args)
    cfg.validate()
    _check_btf_output(args, "leather.btf")
    # the sidecar has grid 0 replaced by the size used (the header keeps 0)
    return _write_btf(args, synthesize, cfg, cfg.resolved())


def run_render(args) -> int:
    from vrneural.btf.pathtrace import load_mitsuba
    from vrneural.btf.pt_render import render_btf

    cfg = config_from_args(RenderConfig, args)
    cfg.validate()
    _check_btf_output(args, "weave.btf")
    load_mitsuba()  # not installed: one line naming the extra, before any output
    return _write_btf(args, render_btf, cfg, cfg, {"height_grid_used": cfg.grid_size})


def _check_btf_output(args, example: str) -> None:
    """--resume with --force, and an output that is not a .btf, are refused."""
    check_resume_force(args.resume, args.force)
    check_suffix(args.output, ".btf", "BTF", example)


def _write_btf(args, make, cfg, sidecar, extra: dict | None = None) -> int:
    """`btf synth` and `btf render`: ``make(cfg, out, ...)`` under the output's lock (a second
    run on it meanwhile is refused), then ``sidecar`` (+ ``extra``) as its config JSON."""
    with output_lock(args.output):
        _check_finished(args.output, args.resume)
        out, _ = check_outputs([args.output, config_path(args.output)], args.force)
        _check_partial(out, args.resume, args.force)
        path = make(cfg, out, resume=args.resume, progress=not args.no_progress, force=args.force)
        write_config(path, sidecar, extra)
    print(path)
    return 0


def _warn_nonfinite(file: str, s: dict) -> None:
    """Warn about NaN/Inf values (``s``: :func:`vrneural.btf.sheet.summary`)."""
    if s["nonfinite_values"]:
        import warnings

        from vrneural.btf.sheet import BtfWarning

        warnings.warn(
            f"{file}: {s['nonfinite_values']} NaN/Inf values"
            f"{' in the sampled slices' if s['value_range_sampled'] else ''}; training refuses "
            "them (re-synthesise or re-import the BTF)",
            BtfWarning,
            stacklevel=2,
        )


def run_info(args) -> int:
    from vrneural.btf.format import read_btf
    from vrneural.btf.sheet import summary

    s = summary(read_btf(args.file))
    _warn_nonfinite(args.file, s)
    if args.json:
        print(json.dumps(s, indent=2, default=str))
        return 0
    sh = s["shape"]
    print(f"file      {s['path']}  ({s['size_bytes'] / 2**20:.1f} MiB)")
    print(
        f"shape     {sh['lights']} lights x {sh['views']} views x {sh['height']}x{sh['width']} "
        f"texels x 3, float16"
    )
    lt, vt = s["light_theta_deg"], s["view_theta_deg"]
    print(
        f"dirs      light theta {lt[0]:.1f}..{lt[1]:.1f} deg, view theta {vt[0]:.1f}..{vt[1]:.1f} "
        f"deg, lights {'==' if s['same_light_and_view_dirs'] else '!='} views"
    )
    tag = " (sampled slices)" if s["value_range_sampled"] else ""
    print(
        f"values    min {s['value_min']:.4g}  max {s['value_max']:.4g}  "
        f"mean {s['value_mean']:.4g}{tag}"
    )
    hf = s["height_field"]
    if hf is not None:
        print(
            f"height    {hf['shape'][0]}x{hf['shape'][1]} height field, {hf['min']:.4g} to "
            f"{hf['max']:.4g} tile widths about the reference plane"
        )
        if hf.get("relief_texels") is not None:
            print(
                f"relief    {hf['relief_texels']:.2f} texels (1st-99th percentile on the texel "
                f"grid): distill --parallax auto gives it {hf['parallax_auto']}"
            )
    m = s["meta"]
    print(f"meta      name={m.get('name')} convention={m.get('convention')} seed={m.get('seed')}")
    gen = m.get("generator")
    print(f"generator {json.dumps(gen)}")
    if isinstance(gen, dict) and gen.get("grid") == 0 and isinstance(gen.get("res"), int):
        used = BtfConfig(res=gen["res"], grid=0).grid_size  # the header keeps the 0 as given
        print(f"          grid 0 = auto: the heightfield was {used}^2 (as the .config.json says)")
    return 0


def run_show(args) -> int:
    from vrneural.btf.format import read_btf
    from vrneural.btf.sheet import contact_sheet, gallery, sheet_panels, summary

    check_suffix(args.output, ".png", "image", "sheet.png", ignore_case=True)
    if len(args.file) > 1 and args.texel:
        raise VrnError(
            f"--texel {args.texel[0]} {args.texel[1]}: picks the unfolded texel of one file's "
            f"contact sheet; a gallery of {len(args.file)} files has none (give one file)"
        )
    btfs = [read_btf(f) for f in args.file]  # every input checked before the output
    if len(btfs) > 1:
        out = check_output(args.output, args.force)
        for f, b in zip(args.file, btfs, strict=True):
            _warn_nonfinite(f, summary(b))
        print(gallery(btfs, out))
        return 0
    (file,), (btf,) = args.file, btfs
    if args.texel:
        _, _, H, W = btf.shape
        check_range("--texel X", args.texel[0], 0, W - 1)
        check_range("--texel Y", args.texel[1], 0, H - 1)
    out = check_output(args.output, args.force)

    _warn_nonfinite(file, summary(btf))  # the sheet shows them as black or white
    print(contact_sheet(btf, out, tuple(args.texel) if args.texel else None))
    for p in sheet_panels(btf):  # say so when this BTF's directions cannot tell pairs apart
        if len(p.names) > 1:
            names = f"{', '.join(p.names[:-1])} and {p.names[-1]}"
            print(
                f"{file}: {names} resolve to the same slice "
                f"(l{p.light} v{p.view}: {p.shown}) among this BTF's {len(btf.light_dirs)} "
                f"lights x {len(btf.view_dirs)} views; one panel shows it, titled with "
                f"{'both' if len(p.names) == 2 else 'all'}",
                file=sys.stderr,
            )
    return 0


def run_import(args) -> int:
    from vrneural.btf.height_import import read_height
    from vrneural.btf.imageset import import_images, plan_import
    from vrneural.btf.ubo2014 import import_ubo, load_extractor, parse_header

    _check_btf_output(args, "leather.btf")  # as btf synth
    _check_finished(args.output, args.resume)
    src, images = args.file, Path(args.file).is_dir()
    if images:  # an image set (vrneural/btf/imageset.py): all checks first
        size = plan_import(src, args.table, args.png_linear, args.height).size
    elif args.table or args.png_linear:
        flag = "--table" if args.table else "--png-linear"
        raise VrnError(f"{flag} is for a folder of images; {src} is not a folder")
    else:
        load_extractor()
        hdr = parse_header(src)
        size = (hdr["height"], hdr["width"])
    height = None if args.height is None else read_height(args.height, args.height_scale, size)
    (out,) = check_outputs([args.output], args.force, inputs=[] if images else [src])
    _check_partial(out, args.resume, args.force)
    if images:
        path = import_images(
            src,
            out,
            table=args.table,
            png_linear=args.png_linear,
            resume=args.resume,
            progress=not args.no_progress,
            height=height,
        )
    else:
        path = import_ubo(src, out, args.resume, not args.no_progress, height)
    print(path)
    return 0
