"""demo/viewer.ipynb executed by nbclient in a real kernel (at the tiny profile, to be quick):
the widget is created, a frame is drawn through the Jupyter backend, the snapshot is in the
notebook's output; one cell added here draws a frame without the HUD and checks it against
the offscreen renderer, bit for bit."""

import base64
import io
import re
from pathlib import Path

import numpy as np
import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "demo" / "viewer.ipynb"
CHECK = """
import numpy as np
from vrneural.viewer.present import compose
view.live.hud = False
widget.force_draw()
shown = np.asarray(widget.snapshot().data)[..., :3]
print("same as offscreen:", bool(np.array_equal(shown, compose(view.replay_offscreen()))))
"""


@pytest.mark.gpu
def test_demo_notebook_runs_and_shows_the_offscreen_frame():
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("jupyter_rfb")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    src = nb.cells[1].source
    assert 'profile="preview"' in src
    nb.cells[1].source = src.replace('profile="preview"', 'profile="tiny", eye_res="96x80"')
    nb.cells.append(nbformat.v4.new_code_cell(CHECK))
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3").execute()
    outs = [c.get("outputs", []) for c in nb.cells if c.cell_type == "code"]
    assert any("application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in outs[0])
    html = next(o["data"]["text/html"] for o in outs[1] if "text/html" in o.get("data", {}))
    b64 = re.search(r"data:image/[\w/]+;base64,([A-Za-z0-9+/=\s]+)'", html).group(1)  # a JPEG
    import imageio.v3 as iio

    img = iio.imread(io.BytesIO(base64.b64decode(b64)))
    assert img.shape[:2] == (80, 96) and np.asarray(img).std() > 5
    text = "".join(o.get("text", "") for o in outs[2] + outs[3])
    assert "'reuse': 2" in text and "GPU ms" in text
    assert "same as offscreen: True" in text
