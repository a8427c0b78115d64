"""Key bindings of `vrneural view`: actions, their default keys and a ``--keys`` TOML file.

Key names are the ones rendercanvas reports (the browser's ``KeyboardEvent.key``): a single
character (``"m"``, ``"["``, ``" "``) or a named key (``"F1"``, ``"Escape"``, ``"Tab"``,
``"ArrowUp"``); ``"Space"`` stands for ``" "``. Letters match with or without Shift.

A key file remaps actions (the others keep their default keys)::

    [keys]
    screenshot = "F12"
    mode = "Tab"

An unknown action, a key name that is not one, or two actions on one key is a one-line error
naming the file and the field, as the scene file's errors do.
"""

from __future__ import annotations

from pathlib import Path

import tomllib

from vrneural.errors import VrnError

#: action -> (default key, what it does); the order is the F1 list's
ACTIONS: dict[str, tuple[str, str]] = {
    "help": ("F1", "show / hide this list"),
    "hud": ("F2", "HUD on / off"),
    "mode": ("m", "mode: texture -> screen -> reference"),
    "reuse_up": ("]", "N + 1 (frames reusing one texture update)"),
    "reuse_down": ("[", "N - 1"),
    "schedule": ("b", "schedule: staggered <-> burst"),
    "precision": ("c", "precision: f32 <-> f16"),
    "radiance": ("g", "radiance textures: per eye <-> shared by both eyes"),
    "adaptive": ("u", "reuse: every N + 1 frames <-> adaptive (--reuse-budget)"),
    "texture_up": ("=", "radiance texture side x 2"),
    "texture_down": ("-", "radiance texture side / 2"),
    "lights": ("0", "all lights on / off"),
    **{f"light_{k}": (str(k), f"light {k} on / off") for k in range(1, 10)},
    "select_light": ("l", "select the next light (drag it with the right mouse button)"),
    "head_path": ("h", "follow the scene's head path (orbit or pose log) / free camera"),
    "camera": ("v", "mouse drag: orbit <-> fly (look around)"),
    "forward": ("w", "fly forward"),
    "back": ("s", "fly back"),
    "left": ("a", "fly left"),
    "right": ("d", "fly right"),
    "down": ("q", "fly down"),
    "up": ("e", "fly up"),
    "reset_camera": ("r", "camera back to the head path's start"),
    "pause": (" ", "pause / resume scene time (moving lights, head path)"),
    "split": ("k", "split view: off -> texture | reference -> texture | FLIP"),
    "screenshot": ("p", "screenshot: PNG + EXR + settings JSON"),
    "quit": ("Escape", "close the window"),
}

#: held keys (the camera moves while they are down); the others act on key_down
HELD = ("forward", "back", "left", "right", "down", "up")

#: named keys rendercanvas reports besides single characters
NAMED = (
    "ArrowDown ArrowUp ArrowLeft ArrowRight Backspace Delete End Enter Escape Home Insert "
    "PageDown PageUp Pause Tab " + " ".join(f"F{k}" for k in range(1, 13))
).split()
ALIASES = {"space": " ", "esc": "Escape", "return": "Enter"}


def normalise(key: str) -> str:
    """The canonical form of a key name: letters lower-case, aliases resolved."""
    if len(key) == 1:
        return key.lower()
    return ALIASES.get(key.lower(), key)


def shown(key: str) -> str:
    """A key as the F1 list writes it."""
    return {" ": "Space"}.get(key, key)


def check_key(key, where: str) -> str:
    """``key`` normalised, or a :class:`VrnError` naming ``where``."""
    if not isinstance(key, str):
        raise VrnError(f"{where} = {key!r} must be a key name (a string)")
    k = normalise(key)
    if (len(k) == 1 and k.isprintable()) or k in NAMED:
        return k
    raise VrnError(
        f'{where} = {key!r} is not a key; use one character ("m", "[") or one of: '
        f"Space, {', '.join(NAMED)}"
    )


class KeyMap:
    """Key -> action, built from the defaults and an optional ``--keys`` file."""

    def __init__(self, overrides: dict[str, str] | None = None, src: str = "keys"):
        keys = {a: k for a, (k, _) in ACTIONS.items()}
        for action, key in (overrides or {}).items():
            if action not in ACTIONS:
                raise VrnError(
                    f"{src}: keys.{action} is not a known action (known: {', '.join(ACTIONS)})"
                )
            keys[action] = check_key(key, f"{src}: keys.{action}")
        by_key: dict[str, str] = {}
        for action, key in keys.items():
            if key in by_key:
                other = by_key[key]
                changed = action if action in (overrides or {}) else other
                raise VrnError(
                    f"{src}: keys.{changed} = {shown(key)!r} is already the key of "
                    f"{other if changed == action else action}; give each action its own key"
                )
            by_key[key] = action
        self.keys, self.by_key = keys, by_key

    def action(self, key: str) -> str | None:
        """The action bound to the reported ``key`` (None when it has none)."""
        return self.by_key.get(normalise(key))

    def help_lines(self) -> list[str]:
        """The F1 list: one ``key  what it does`` line per action, then the mouse."""
        lines = [f"{shown(self.keys[a]):>6}  {what}" for a, (_, what) in ACTIONS.items()]
        return [
            *lines,
            "  drag  left: orbit (fly: look); middle: pan; right: move the selected light",
            " wheel  zoom (fly: speed)",
        ]


def load_keys(path: str | Path) -> KeyMap:
    """A :class:`KeyMap` from a TOML file with one ``[keys]`` table (errors name the file)."""
    p = Path(path)
    if not p.is_file():
        raise VrnError(f"{p}: key file not found")
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8-sig"))
    except tomllib.TOMLDecodeError as e:
        raise VrnError(f"{p}: invalid TOML ({e})") from None
    except UnicodeDecodeError:
        raise VrnError(f"{p}: not a text file (a key file is TOML)") from None
    extra = sorted(set(data) - {"keys"})
    if extra:
        raise VrnError(f"{p}: {extra[0]} is not a known table (a key file has one: [keys])")
    table = data.get("keys", {})
    if not isinstance(table, dict):
        raise VrnError(f"{p}: keys must be a table ([keys])")
    return KeyMap(table, str(p))
