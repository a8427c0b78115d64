#!/usr/bin/env bash
# Idempotent set-up for a fresh Debian machine (also used by CI):
#   1. a virtual environment in .venv
#   2. the pinned PyTorch (a CPU build: see VRNEURAL_TORCH_INDEX below), installed BEFORE the
#      package, so pip never resolves a bare `torch` (which would pull several GB of CUDA
#      packages)
#   3. vrneural itself, editable, with the train/dev/metrics/view/render/docs extras (render:
#      Mitsuba 3, `btf render`; docs: mkdocs-material and mkdocstrings, the documentation
#      site), and btf-extractor (UBO2014 import; built without isolation, see below)
#   4. Mesa's lavapipe CPU Vulkan driver, only when wgpu finds no Vulkan (or Metal, D3D12)
#      adapter (an OpenGL one, e.g. llvmpipe through EGL, does not count)
#   5. Xvfb and the X11 libraries glfw loads (`vrneural view`; its window tests start an
#      Xvfb), when missing
# Re-running is cheap: steps 2-3 are skipped while pyproject.toml is unchanged.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"   # quiets Mesa's harmless warning
PY="${PYTHON:-python3}"
TORCH_SPEC="${VRNEURAL_TORCH:-torch==2.13.0}"
# Where pip finds that torch. Unset: pip's own configuration (on this project's machines a
# local CPU wheel). On a machine whose pip reads plain PyPI, where the Linux wheel of that
# version is the CUDA build, set VRNEURAL_TORCH_INDEX=https://download.pytorch.org/whl/cpu.
TORCH_INDEX=()
[ -n "${VRNEURAL_TORCH_INDEX:-}" ] && TORCH_INDEX=(--index-url "$VRNEURAL_TORCH_INDEX")

if [ ! -x .venv/bin/python ]; then
    echo "[setup] creating .venv"
    "$PY" -m venv .venv
fi
stamp=.venv/.vrneural-setup
want="$(cat pyproject.toml scripts/setup.sh | sha256sum | cut -c1-16) $TORCH_SPEC ${VRNEURAL_TORCH_INDEX:-}"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    echo "[setup] installing $TORCH_SPEC (CPU) and vrneural[train,dev,metrics,view,render,docs] into .venv"
    .venv/bin/python -m pip install -q --disable-pip-version-check "${TORCH_INDEX[@]}" "$TORCH_SPEC"
    .venv/bin/python -m pip install -q --disable-pip-version-check -e ".[train,dev,metrics,view,render,docs]"
    # UBO2014 import: btf-extractor's own build pins numpy<1.20 (no Python 3.11 build), so it
    # is built against the installed numpy without build isolation.
    echo "[setup] building btf-extractor (UBO2014 import) against the installed numpy"
    .venv/bin/python -m pip install -q --disable-pip-version-check poetry-core "Cython<0.30"
    .venv/bin/python -m pip install -q --disable-pip-version-check --no-deps \
        --no-build-isolation btf-extractor
    echo "$want" > "$stamp"
fi

if ! .venv/bin/python -c "from vrneural.gpu.device import _adapter; _adapter()" >/dev/null 2>&1; then
    echo "[setup] wgpu finds no Vulkan adapter: installing Mesa's lavapipe (mesa-vulkan-drivers)"
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi

# the viewer: Xvfb, and the X11 client libraries the glfw wheel's own libglfw loads
view_pkgs=(xvfb libx11-6 libx11-xcb1 libxrandr2 libxinerama1 libxcursor1 libxi6 libxext6 libxrender1)
missing=()
for p in "${view_pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "[setup] installing ${missing[*]} (the viewer's window and its tests under Xvfb)"
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
