"""Shared fixtures: the example scenes at tiny sizes, and the command-line tool to compare with."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import implicit_psdr as ip

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def scene_dict(name, width=16, height=12, spp=4):
    """The example scene ``scenes/<name>.json`` as a dict, at a tiny image size and spp; grid files
    made absolute, so the dict loads from anywhere."""
    doc = json.loads((SCENES / f"{name}.json").read_text())
    doc["camera"]["width"], doc["camera"]["height"] = width, height
    doc["spp"] = spp

    def absolute(node):
        if isinstance(node, dict):
            if node.get("type") == "grid":
                node["file"] = str(SCENES / node["file"])
            for v in node.values():
                absolute(v)
        elif isinstance(node, list):
            for v in node:
                absolute(v)

    absolute(doc["shapes"])
    return doc


@pytest.fixture
def small():
    """A factory of tiny example scenes: ``small("sphere_floor")`` -> (Scene, dict)."""

    def make(name, **size):
        doc = scene_dict(name, **size)
        return ip.Scene.from_dict(doc), doc

    return make


def installed_cli():
    """The ``implicit-psdr`` command this package installed beside the interpreter, or None."""
    path = Path(sys.executable).parent / "implicit-psdr"
    return str(path) if path.exists() else None


def cargo_cli():
    """The Rust binary target/release/implicit-psdr, built with cargo if it is missing (it reuses the
    release build of the dependencies the package made); skips the test without cargo."""
    path = ROOT / "target/release/implicit-psdr"
    if not path.exists():
        if shutil.which("cargo") is None:
            pytest.skip("no implicit-psdr binary and no cargo to build it")
        subprocess.run(
            ["cargo", "build", "--release", "--bin", "implicit-psdr"], cwd=ROOT, check=True
        )
    return str(path)


@pytest.fixture(scope="session")
def cli():
    """The command-line tool: $IMPLICIT_PSDR_CLI, else the ``implicit-psdr`` command of this package,
    else the Rust binary (see ``cargo_cli``)."""
    path = os.environ.get("IMPLICIT_PSDR_CLI") or installed_cli() or cargo_cli()

    def run(*args, cwd):
        result = subprocess.run([path, *map(str, args)], cwd=cwd, capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        return result.stdout

    return run


def write_scene(doc, folder):
    """Writes ``doc`` as ``folder/scene.json`` and returns its path."""
    path = Path(folder) / "scene.json"
    path.write_text(json.dumps(doc))
    return path
