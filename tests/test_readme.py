"""The README's quick start runs as written: its ``moorjax`` commands (in this
process, so they share one compilation with the Python block) and its Python
blocks, in a scratch folder."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from moorjax.cli import main

README = Path(__file__).resolve().parents[1] / "README.md"


def quick_start_blocks():
    text = README.read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```(bash|python)\n(.*?)```", section, flags=re.S)


@pytest.mark.slow
def test_quick_start_runs(tmp_path, monkeypatch):
    blocks = quick_start_blocks()
    assert [k for k, _ in blocks] == ["bash", "python", "python"]
    monkeypatch.chdir(tmp_path)
    err = io.StringIO()
    for line in blocks[0][1].splitlines():
        argv = shlex.split(line, comments=True)
        assert argv[0] == "moorjax", line
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            assert main(argv[1:]) == 0, (line, err.getvalue())
    assert (tmp_path / "run.nc").is_file() and (tmp_path / "run.png").stat().st_size > 10_000
    for _, code in blocks[1:]:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, str(README), "exec"), {})
        assert out.getvalue().strip()
    # the fairlead tension printed by the first block oscillates (the example moves)
    import xarray as xr

    ds = xr.open_dataset(tmp_path / "run.nc")
    tb = ds["tension_b"].sel(line=1).values
    assert tb.max() - tb.min() > 0.5 * tb.mean()
