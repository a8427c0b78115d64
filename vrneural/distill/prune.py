"""``distill --init-from``: start a narrow network from a wider trained one, pruned.

An 8-wide network trained from random weights ends in a worse and more seed-dependent minimum
than the same 8-wide network cut out of a 16-wide one after part of the budget (docs/training.md;
research log). Pruning keeps, in every hidden layer, the ``width`` units with the
largest importance

    importance_j = std(a_j) * ||W_next[:, j]||

(``a_j`` the unit's activation over a fixed set of training slices at texel centres, ``W_next``
the weights that read it), and folds each dropped unit's mean activation into the next layer's
bias, so a dropped unit that barely varies costs nothing. Layers are pruned from the input
side, each on the activations of the already-pruned network before it. Textures are kept. For
the coarse-to-fine student the coarse MLP's last layer is z_c, read by the first ``Z`` inputs
of M_f.

Deterministic: the slices are every k-th training pair (at most :data:`SLICES`), no jitter.
"""

from __future__ import annotations

import warnings

import torch

from vrneural.distill.checkpoint import UnfinishedRunWarning, unfinished_run
from vrneural.distill.data import SliceData
from vrneural.distill.models import NeuralModel
from vrneural.errors import VrnError

SLICES = 64


@torch.no_grad()
def prune_to(wide: NeuralModel, spec: dict, data: SliceData) -> NeuralModel:
    """A :class:`NeuralModel` of ``spec`` (hidden widths <= ``wide``'s, everything else
    equal) holding ``wide``'s pruned weights and its textures (every tensor is the wide
    network's, so nothing depends on a seed)."""
    net = NeuralModel(spec)
    state = {k: v.clone() for k, v in wide.state_dict().items()}
    # the layer chains whose hidden units are pruned: (state prefix, layer count, widths)
    if spec["arch"] == "single":
        chains = [("mlp", len(spec["hidden"]) + 1, spec["hidden"])]
    else:
        chains = [
            ("coarse", len(spec["coarse_hidden"]), spec["coarse_hidden"]),
            ("fine", len(spec["fine_hidden"]) + 1, spec["fine_hidden"]),
        ]
    for name, n_layers, widths in chains:
        for i, keep in enumerate(widths):
            mean, std = _activations(wide, state, data, name, i)  # of the pruned-so-far net
            w_next, b_next, cols = _reader(state, name, i, n_layers)
            imp = std * w_next[:, cols].norm(dim=0)
            order = torch.argsort(imp, descending=True, stable=True)
            kept = order[:keep].sort().values
            dropped = order[keep:]
            # the dropped units' mean output goes into the bias that read it
            state[b_next] = state[b_next] + w_next[:, cols[dropped]] @ mean[dropped]
            w = f"{name}.layers.{i}"
            state[f"{w}.weight"] = state[f"{w}.weight"][kept]
            state[f"{w}.bias"] = state[f"{w}.bias"][kept]
            read = torch.ones(w_next.shape[1], dtype=torch.bool)  # the reader keeps the rest
            read[cols[dropped]] = False
            state[b_next.removesuffix("bias") + "weight"] = w_next[:, read]
    net.load_state_dict(state)
    return net


def _reader(state: dict, name: str, i: int, n_layers: int):
    """The layer that reads hidden layer ``i`` of chain ``name``: its weight, its bias key and
    the columns of its input that are that layer's units."""
    if i + 1 < n_layers:  # the next layer of the same chain reads all of it
        w = state[f"{name}.layers.{i + 1}.weight"]
        return w, f"{name}.layers.{i + 1}.bias", torch.arange(w.shape[1])
    # the coarse MLP's last layer (z_c) is read by M_f's first layer, as its first Z inputs
    z = state[f"{name}.layers.{i}.weight"].shape[0]
    w = state["fine.layers.0.weight"]
    return w, "fine.layers.0.bias", torch.arange(z)


def _activations(wide: NeuralModel, state: dict, data: SliceData, name: str, i: int):
    """Mean and standard deviation per unit of layer ``i`` of chain ``name`` of the network in
    ``state`` (pruned up to there), over the fixed slices (float64 sums: no activations kept)."""
    probe = NeuralModel(_spec_of(wide.spec, state)).to(data.device)
    probe.load_state_dict(state)
    uv = data.uv(None, shard=False)
    step = max(1, len(data.train) // SLICES)
    total = total_sq = 0.0
    count = 0
    for pair in data.train[::step][:SLICES]:
        wi, wo = data.dirs(pair)
        a = probe.activations(wi, wo, uv)[1][name][i]
        a = a.reshape(-1, a.shape[-1]).double()
        total = total + a.sum(0)
        total_sq = total_sq + (a * a).sum(0)
        count += a.shape[0]
    mean = total / count
    var = (total_sq / count - mean * mean).clamp_min(0.0)
    return mean.float(), var.sqrt().float()


def _spec_of(spec: dict, state: dict) -> dict:
    """``spec`` with the hidden widths the (partly pruned) weights in ``state`` have."""
    s = dict(spec)

    def widths(name, n):
        return [int(state[f"{name}.layers.{j}.weight"].shape[0]) for j in range(n)]

    if s["arch"] == "single":
        s["hidden"] = widths("mlp", len(s["hidden"]))
    else:
        s["coarse_hidden"] = widths("coarse", len(s["coarse_hidden"]))
        s["fine_hidden"] = widths("fine", len(s["fine_hidden"]))
    return s


WIDTH_KEYS = ("hidden", "coarse_hidden", "fine_hidden")


def check_init(path: str, ick: dict, cfg, spec: dict, teacher_sha: str) -> None:
    """``--init-from``: a run of this method, from this teacher (so the same BTF and split:
    its weights never saw this run's held-out slices), of this architecture at this width or
    wider. One-line error otherwise."""
    where = f"--init-from {path}"
    if cfg.method == "neumip":
        raise VrnError(f"{where}: --init-from prunes the 8-wide networks (student, single8)")
    if ick.get("method") != cfg.method:
        raise VrnError(
            f"{where}: is a {ick.get('method')} run; this run trains {cfg.method} "
            f"(train the wide run with --method {cfg.method} --width 16)"
        )
    if ick.get("teacher", {}).get("sha256") != teacher_sha:
        raise VrnError(
            f"{where}: was distilled from another teacher than {cfg.teacher}; its "
            "training slices may be this run's held-out ones (use a run of this teacher)"
        )
    theirs = ick["spec"]
    for k in sorted(set(spec) | set(theirs)):
        if k in WIDTH_KEYS:
            mine, wide = spec.get(k), theirs.get(k)
            if not isinstance(wide, list) or len(wide) != len(mine):
                raise VrnError(f"{where}: its {k} {wide} has another depth than {mine}")
            if any(w < m for w, m in zip(wide, mine, strict=True)):
                raise VrnError(
                    f"{where}: is {max(wide)} wide, narrower than --width {cfg.width}; "
                    f"--init-from needs a run at least {cfg.width} wide (train one with "
                    f"--width {max(16, 2 * cfg.width)}), or ask for --width {max(wide)} or less"
                )
        elif k not in ("tex_init",) and spec.get(k) != theirs.get(k):
            name, show = SPEC_FLAGS.get(k, (k, lambda v: v))
            raise VrnError(
                f"{where}: was trained with {name} {show(theirs.get(k))}, this run with "
                f"{show(spec.get(k))}"
            )
    if not ick.get("finished", True):
        warnings.warn(
            f"{path}: {unfinished_run(ick)}; starting from it as it is",
            UnfinishedRunWarning,
            stacklevel=2,
        )


#: spec fields -> the option that sets them and its value, for --init-from's messages
SPEC_FLAGS = {
    "output": ("--space", lambda v: "log" if v == "log1p" else "linear"),
    "coarse_channels": ("--coarse-channels", lambda v: v),
    "fine_channels": ("--fine-channels", lambda v: v),
    "channels": ("texture channels", lambda v: v),
    "dir_inputs": ("--neumip-dirs", lambda v: v),
    "tex_res": ("the BTF resolution", lambda v: "x".join(map(str, v))),
    "coarse_res": ("the BTF resolution / 2", lambda v: "x".join(map(str, v))),
    "fine_res": ("the BTF resolution", lambda v: "x".join(map(str, v))),
}
