"""`vrneural` entry point and `vrneural info`."""

import json
import subprocess
import sys

import pytest

from vrneural.cli import COMMANDS, main


def _run(*args, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "vrneural", *args], capture_output=True, text=True, timeout=timeout
    )


def test_help_lists_only_registered_commands(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    for name in COMMANDS:
        assert name in out


def test_unknown_command_exits_2():
    r = _run("frobnicate")
    assert r.returncode == 2 and "invalid choice" in r.stderr


def test_bad_texels_is_one_line_error():
    r = _run("info", "--texels", "5")
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "--texels" in r.stderr


@pytest.mark.gpu
def test_info_json():
    r = _run("info", "--json", "--texels", "65536")
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    assert info["adapter"]["name"]
    assert {"shader-f16", "timestamp-query", "subgroup"} <= set(info["adapter"]["features"])
    assert info["adapter"]["limits"]["max_texture_dimension_2d"] > 0
    precisions = [t["precision"] for t in info["mlp_throughput"]]
    assert precisions[0] == "f32"
    for t in info["mlp_throughput"]:
        assert t["evals_per_s"] > 0 and t["gflops"] > 0
    assert info["versions"]["wgpu"] and info["versions"]["numpy"]


@pytest.mark.gpu
def test_info_human():
    r = _run("info", "--texels", "65536")
    assert r.returncode == 0, r.stderr
    for word in ("adapter", "features", "limits", "MLP f32", "versions"):
        assert word in r.stdout


def test_ctrl_c_while_the_commands_load_is_one_line(monkeypatch, capsys):
    """Ctrl-C in the first half second (the subcommand modules importing) was a traceback."""
    import vrneural.cli as cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    assert cli.main(["info"]) == 130
    assert capsys.readouterr().err == "vrneural: interrupted\n"


def test_config_switches_off_by_default_have_no_negative_form():
    import argparse
    import dataclasses

    from vrneural.config import add_config_args, config_from_args, opt

    @dataclasses.dataclass
    class C:
        force: bool = opt(False, "overwrite")
        progress: bool = opt(True, "bar")

    p = argparse.ArgumentParser()
    add_config_args(p, C)
    helps = p.format_help()
    assert "--force" in helps and "--no-force" not in helps and "--no-progress" in helps
    c = config_from_args(C, p.parse_args(["--force", "--no-progress"]))
    assert c.force is True and c.progress is False
    assert config_from_args(C, p.parse_args([])) == C()
    with pytest.raises(SystemExit):
        p.parse_args(["--no-force"])


def test_an_ignored_sigterm_stays_ignored_and_sigint_is_taken_even_so():
    """`trap '' TERM` (or nohup-like wrappers) means the user wants SIGTERM ignored: neither
    the CLI nor a training/render loop's Stop takes it. SIGINT is taken even when ignored, as
    shells start background jobs with it ignored."""
    import signal

    from vrneural.interrupt import Stop, terminate_as_interrupt

    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        assert terminate_as_interrupt() is None
        with Stop():
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
            assert getattr(signal.getsignal(signal.SIGINT), "__func__", None) is Stop._handle
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def test_main_in_process_leaves_the_signal_handlers_as_it_found_them(capsys):
    import signal

    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    assert main(["info", "--texels", "5"]) == 2
    assert before == {s: signal.getsignal(s) for s in before}
