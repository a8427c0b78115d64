"""Device profiles: named configs (not if-chains). ``quest3`` is the paper's target."""

from __future__ import annotations

from dataclasses import dataclass

from vrneural.errors import VrnError


@dataclass(frozen=True)
class Profile:
    """What a headset asks of the renderer."""

    name: str
    eye_res: tuple[int, int]  # (width, height) pixels per eye
    fps: float  # display rate, Hz
    texture_res: int  # radiance texture side per eye per object
    reuse: int  # N: frames that reuse one update (every N + 1 frames share one)
    lights: int  # point lights in the default scene
    fov_y: float  # vertical field of view, degrees
    ipd: float = 0.063  # metres


PROFILES: dict[str, Profile] = {
    p.name: p
    for p in (
        # Meta Quest 3: 2064 x 2208 per eye, 90 Hz; the paper's 1200^2 texture and N = 4.
        Profile("quest3", (2064, 2208), 90.0, 1200, 4, 3, 96.0),
        # Quest 2-class headset.
        Profile("quest2", (1832, 1920), 90.0, 1024, 4, 3, 94.0),
        # Small and fast: tests and smoke runs on CPU adapters.
        Profile("tiny", (96, 96), 90.0, 128, 4, 2, 90.0),
        # A desktop preview at a moderate size.
        Profile("preview", (960, 1024), 90.0, 800, 4, 3, 96.0),
    )
}


def get_profile(name: str) -> Profile:
    if name not in PROFILES:
        raise VrnError(f"--profile = {name!r} is not allowed; choose one of: {', '.join(PROFILES)}")
    return PROFILES[name]
