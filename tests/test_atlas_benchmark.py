"""`python -m vrneural.atlas.benchmark`: documented options, one-line errors (exit 2) before any
work, and a tiny run."""

import json

import pytest

from vrneural.atlas import benchmark


def _run(capsys, argv):
    """(exit code, stderr lines) of the command line; argparse's own errors exit."""
    try:
        rc = benchmark.main(argv)
    except SystemExit as e:
        rc = e.code
    return rc, capsys.readouterr().err.strip().splitlines()


def test_help_documents_every_option_with_its_default(capsys):
    with pytest.raises(SystemExit):
        benchmark.main(["--help"])
    out = " ".join(capsys.readouterr().out.split())  # as wrapped for any terminal width
    for default in ("highpoly", "1200", "2", "3", "atlas_bench.json"):
        assert f"(default: {default})" in out, out
    assert "even, in [8, 8192]" in out and "overwrite existing outputs" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["--res", "63"],
            "--res = 63 must be even (2x2 blocks); allowed: even values in [8, 8192]",
        ),
        (["--res", "8194"], "--res = 8194 is out of range; allowed [8, 8192]"),
        (["--repeats", "0"], "--repeats = 0 is out of range; allowed [1, 1000]"),
        (["--padding", "-1"], "--padding = -1 is out of range; allowed [0, 64]"),
        (["--mesh", "teapot"], "argument --mesh: invalid choice: 'teapot'"),
        (["--res", "big"], "argument --res: invalid int value: 'big'"),
        (["-o", "chart.png"], "the PNG chart is written beside the JSON, with suffix .png"),
    ],
)
def test_errors_are_one_line_with_exit_2(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    rc, err = _run(capsys, argv)
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("python -m vrneural.atlas.benchmark: error: ") and message in err[0]
    assert not list(tmp_path.iterdir())  # refused before any work


def test_a_tiny_run_writes_json_and_png_and_refuses_to_overwrite(capsys, tmp_path):
    out = tmp_path / "b.json"
    argv = ["--mesh", "plane", "--res", "64", "--repeats", "1", "-o", str(out)]
    assert benchmark.main(argv) == 0
    assert "(median of 1)" in capsys.readouterr().out
    res = json.loads(out.read_text())
    assert res["resolution"] == 64 and len(res["runs"]) == 1
    assert out.with_suffix(".png").read_bytes()[:4] == b"\x89PNG"
    rc, err = _run(capsys, argv)
    assert rc == 2 and len(err) == 1 and "output exists; pass --force" in err[0], err
