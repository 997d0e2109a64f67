"""The README's Python examples run as written, so they cannot go stale: every
```python block of its Python section, from a working directory laid out as a clone
(the repository with shared/data beside it)."""

import os
import re
import runpy
from pathlib import Path

import pytest

from conftest import REPO, data_root, require

SECTION = "## Python"


def python_blocks():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    section = text[start:end if end >= 0 else None]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


BLOCKS = python_blocks()


def test_the_section_has_the_examples():
    assert len(BLOCKS) >= 2
    assert any("swarmpose.register(" in b for b in BLOCKS)
    assert any(".track(" in b for b in BLOCKS)


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_block_runs(index, tmp_path, monkeypatch):
    code = BLOCKS[index]
    paths = re.findall(r'"\.\./shared/data/([^"/]+)"', code)
    for name in paths:
        d = data_root() / name
        require(f"data set {d}", d.is_dir(), "set SWARMPOSE_DATA to the data root")
    # A clone's layout: <tmp>/repo is the working directory, <tmp>/shared/data the data.
    (tmp_path / "shared").mkdir()
    os.symlink(data_root(), tmp_path / "shared" / "data")
    (tmp_path / "repo").mkdir()
    monkeypatch.chdir(tmp_path / "repo")
    script = tmp_path / f"readme_block_{index}.py"
    script.write_text(code, encoding="utf-8")
    runpy.run_path(str(script), run_name="__main__")


def test_open3d_example_runs_or_skips():
    """The Open3D comparison runs to the end (or says it skipped without Open3D)."""
    import subprocess
    import sys

    script = Path(__file__).resolve().parents[1] / "examples" / "open3d_compare.py"
    out = subprocess.run([sys.executable, str(script), "-n", "200"], check=True,
                         capture_output=True, text=True).stdout
    try:
        import open3d  # noqa: F401
    except ImportError:
        assert out.startswith("skipped: open3d is not installed or cannot be loaded")
        return
    assert "swarmpose" in out and "open3d" in out and "90%" in out
