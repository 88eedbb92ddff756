"""The ``implicit-psdr`` command that ``pip install .`` puts on PATH: the same tool as the Rust
binary, byte for byte in what it writes, and in its messages and exit codes."""

import subprocess
import sys

import pytest

from conftest import ROOT, cargo_cli, installed_cli, scene_dict, write_scene


def run(command, *args, cwd):
    return subprocess.run([*command, *map(str, args)], cwd=cwd, capture_output=True, text=True)


def commands():
    """The installed command, ``python -m implicit_psdr``, and the Rust binary."""
    installed = installed_cli()
    if installed is None:
        pytest.skip("the package's implicit-psdr command is not installed beside this Python")
    return [[installed], [sys.executable, "-m", "implicit_psdr"], [cargo_cli()]]


def test_the_installed_command_writes_what_the_binary_writes(tmp_path):
    scene = write_scene(scene_dict("sphere_floor"), tmp_path)
    outputs = []
    for k, command in enumerate(commands()):
        out, png = tmp_path / f"{k}.exr", tmp_path / f"{k}.png"
        result = run(command, "render", scene, "--out", out, "--png", png, cwd=tmp_path)
        assert result.returncode == 0, result.stderr
        outputs.append((out.read_bytes(), png.read_bytes()))
    assert all(o == outputs[0] for o in outputs)


def test_the_installed_command_fails_as_the_binary_does(tmp_path):
    for command in commands():
        result = run(command, "render", ROOT / "scenes/sphere_floor.json", "--sp", "4", cwd=tmp_path)
        assert result.returncode == 2
        assert result.stderr == "error: unexpected argument '--sp' found (see --help)\n"
        help = run(command, "--help", cwd=tmp_path)
        assert help.returncode == 0 and "Usage: implicit-psdr" in help.stdout
    assert list(tmp_path.iterdir()) == []
