"""The README's Python example is examples/python/quickstart.py, and its output is what the README
says it is (the radius's path to 1), so the README's numbers cannot drift from the package's."""

import re
import subprocess
import sys

from conftest import ROOT


def readme_python_block():
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python"):]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def test_the_readme_example_is_the_quickstart_and_prints_what_it_says():
    example = (ROOT / "examples/python/quickstart.py").read_text()
    assert example.split("\n", 1)[1] == readme_python_block()
    out = subprocess.run([sys.executable, str(ROOT / "examples/python/quickstart.py")], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    radii = [float(r) for r in re.findall(r"radius (\d\.\d+)", out)]
    assert len(radii) == 8, out
    claim = re.search(r"the radius goes ([\d.→ ]+?) and stays within ([\d.]+) of 1",
                      (ROOT / "README.md").read_text())
    path = [float(x) for x in claim.group(1).split("→")]
    assert path[0] == 0.8
    assert [round(r, 2) for r in radii[: len(path) - 1]] == path[1:], out
    tolerance = float(claim.group(2))
    assert all(abs(r - 1) < tolerance for r in radii[len(path) - 1:]), out
