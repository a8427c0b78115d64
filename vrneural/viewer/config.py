"""``ViewConfig``: what `vrneural view` takes besides `run`'s options (each field's help is its
--help line), and the start-up checks shared by the command and :class:`~vrneural.viewer.View`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from vrneural.config import opt
from vrneural.errors import VrnError, check_int
from vrneural.outputs import check_output

SPLITS = ("off", "reference", "flip")
#: `run` options the viewer has no use for: it writes no run directory
RUN_ONLY = ("scene", "frames", "out", "video", "video_scale", "save_frames", "force")


@dataclass
class ViewConfig:
    frames: int = opt(0, "close the window after N frames (0: when it is closed)")
    record: str = opt("", "write what the window shows to OUT.mp4 (H.264, the profile's fps)")
    shots: str = opt("out/view", "directory of the screenshots P saves (PNG + EXR + JSON)")
    keys: str = opt("", 'key bindings (TOML: [keys] action = "key"; F1 lists the actions)')
    split: str = opt("off", "split view at start: off | reference | flip", choices=SPLITS)
    split_every: int = opt(
        0,
        "frames between refreshes of the split view's reference and FLIP map "
        "(default: 1, or 30 on a CPU adapter, where the per-pixel teacher takes seconds)",
    )
    window: str = opt(
        "", "window size WIDTHxHEIGHT (default: the eyes side by side, shrunk to fit 1920x1080)"
    )
    hud: bool = opt(True, "show the HUD (F2 toggles it)")
    vsync: bool = opt(False, "wait for the display's refresh (adds up to a refresh of latency)")
    force: bool = opt(False, "overwrite --record's file")


def check_view_config(vc: ViewConfig) -> None:
    """Range and file checks before anything opens (one-line errors, as `run`'s)."""
    if not isinstance(vc, ViewConfig):
        raise VrnError(f"view: config is a {type(vc).__name__}, expected a ViewConfig")
    check_int("--frames", vc.frames, 0, 10_000_000)
    check_int("--split-every", vc.split_every, 0, 100_000)
    if vc.split not in SPLITS:
        raise VrnError(f"--split = {vc.split!r} is not allowed; choose {', '.join(SPLITS)}")
    if vc.window:
        from vrneural.runtime.config import parse_res

        parse_res(vc.window, "--window")
    if vc.keys:
        from vrneural.viewer.keys import load_keys

        load_keys(vc.keys)
    if vc.record:
        if not str(vc.record).lower().endswith(".mp4") or Path(vc.record).name.lower() == ".mp4":
            raise VrnError(f"--record = {vc.record!r} must name an .mp4 file (e.g. out/view.mp4)")
        from vrneural.runtime.output import check_video

        check_output(vc.record, vc.force)
        check_video()
    if not str(vc.shots).strip():
        raise VrnError("--shots is empty; name a directory for the screenshots")
    shots = Path(vc.shots)
    if shots.exists() and not shots.is_dir():
        raise VrnError(f"--shots = {vc.shots!r} is a file; name a directory")
