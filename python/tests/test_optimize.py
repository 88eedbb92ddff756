"""optimize: the rows of a run against the command-line tool's progress.csv (from a file and from a
dict, with and without an output folder), the files it writes, and its errors."""

import csv
import json
import math

import pytest

import implicit_psdr as ip
from conftest import ROOT

INVERSE = ROOT / "scenes" / "inverse"


def tiny(example, **changes):
    """The example ``scenes/inverse/<example>/opt.json`` as a dict, cut down to seconds of work,
    its scenes named by absolute paths (so it runs from any folder)."""
    doc = json.loads((INVERSE / example / "opt.json").read_text())
    doc["scene"] = str(INVERSE / example / doc["scene"])
    doc["target"] = {"scene": str(INVERSE / example / doc["target"]["scene"])}
    doc.update({"iterations": 4, "spp": 2, "target_spp": 8, **changes})
    return doc


def read_progress(path):
    """The rows of a progress.csv as the function returns them."""
    with open(path, newline="") as f:
        return [
            {k: int(v) if k == "iteration" else float(v) for k, v in row.items()}
            for row in csv.DictReader(f)
        ]


def assert_same_rows(rows, expected):
    """Same columns, and every number but the times bit for bit (NaN for NaN)."""
    assert len(rows) == len(expected) > 0
    for row, want in zip(rows, expected):
        assert list(row) == list(want)
        for column, value in row.items():
            if column.endswith("seconds"):
                continue
            same = value == want[column] or (math.isnan(value) and math.isnan(want[column]))
            assert same, (row["iteration"], column, value, want[column])


def test_named_parameters_match_the_cli(cli, tmp_path):
    doc = tiny("named")
    (tmp_path / "opt.json").write_text(json.dumps(doc))
    cli("optimize", "opt.json", "--out", "out", cwd=tmp_path)
    expected = read_progress(tmp_path / "out" / "progress.csv")
    assert list(expected[0]) == [
        "iteration", "loss", "seconds", "gradient_norm", "loss_pass_seconds", "interior_seconds",
        "primary_seconds", "secondary_seconds", "grid_edit_seconds",
    ]
    # From the file, and from the dict; neither writes anything without `out`.
    from_file = ip.optimize(tmp_path / "opt.json")
    assert_same_rows(from_file, expected)
    assert_same_rows(ip.optimize(doc), expected)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["opt.json", "out"]
    assert [r["iteration"] for r in from_file] == [0, 1, 2, 3]
    assert isinstance(from_file[0]["iteration"], int) and from_file[0]["loss"] > 0


def test_grid_run_writes_the_cli_files(cli, tmp_path):
    # The blob: shape metrics, a refinement and redistancing; files relative to base_dir.
    cli_doc = tiny("blob", views_per_iteration=2, upsample_at=[2], redistance_every=2,
                   snapshot_every=2)
    doc = dict(cli_doc, scene="start.json")
    (tmp_path / "opt.json").write_text(json.dumps(cli_doc))
    cli("optimize", "opt.json", "--out", "cli", cwd=tmp_path)
    rows = ip.optimize(doc, tmp_path / "py", base_dir=INVERSE / "blob", threads=1)
    expected = read_progress(tmp_path / "cli" / "progress.csv")
    assert "iou" in expected[0] and "chamfer" in expected[0]
    assert_same_rows(rows, expected)
    assert_same_rows(read_progress(tmp_path / "py" / "progress.csv"), expected)
    # The scene files and the target cache, byte for byte; result.json's other grids resolve alike.
    for name in ["blob.npy", "result.json", "views.png", "targets/targets.json",
                 "targets/view_0.exr", "snapshots/views_00002.png"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert ip.Scene.load(tmp_path / "py" / "result.json").grid("blob").shape == (31, 31, 31)


def test_bad_configs_name_the_field(tmp_path):
    with pytest.raises(ip.SceneError, match=r"^config: iterations: "):
        ip.optimize(tiny("named", iterations=0))
    with pytest.raises(ip.SceneError, match=r"^config: iteration: unknown field"):
        ip.optimize(dict(tiny("named"), iteration=3))
    with pytest.raises(ip.SceneError, match=r"^config: iterations: must be a finite number"):
        ip.optimize(dict(tiny("named"), iterations=math.nan))
    with pytest.raises(ip.SceneError, match=r"opt.json: "):
        ip.optimize(tmp_path / "opt.json")
    (tmp_path / "file").write_text("")
    with pytest.raises(ip.SceneError, match=r"file: is not a folder$"):
        ip.optimize(tiny("named"), tmp_path / "file")
