"""Tests for moorjax.io.motion: the prescribed-motion CSV reader (pure Python, no JAX)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from moorjax.io.errors import InputError, InputWarning
from moorjax.io.motion import Motion, read_motion


def _surge(t):
    x = -5.2 + 5.0 * np.sin(2 * np.pi * t / 10.0)
    vx = 5.0 * 2 * np.pi / 10.0 * np.cos(2 * np.pi * t / 10.0)
    return x, vx


def _write(tmp_path: Path, text: str, name: str = "motion.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _good_csv(tmp_path: Path) -> tuple[Path, np.ndarray]:
    t = np.arange(0.0, 1.0001, 0.01)
    x, vx = _surge(t)
    rows = ["t,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz"]
    rows += [f"{ti:.2f},{xi:.10f},0.0,-70.0,{vi:.10f},0.0,0.0" for ti, xi, vi in zip(t, x, vx)]
    return _write(tmp_path, "\n".join(rows) + "\n"), t


def _raises(path: Path, point_ids, *fragments: str) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        with pytest.raises(InputError) as info:
            read_motion(path, point_ids)
    msg = str(info.value)
    assert str(path) in msg, msg
    for f in fragments:
        assert f in msg, f"{f!r} not in {msg!r}"
    return msg


HEADER3 = "t,P2_x,P2_y,P2_z\n"


# ----------------------------------------------------------------------------
# good files
# ----------------------------------------------------------------------------


def test_round_trip_with_velocities(tmp_path):
    path, t = _good_csv(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = read_motion(path, [2])
    assert isinstance(m, Motion)
    assert m.path == str(path)
    x, vx = _surge(t)
    np.testing.assert_allclose(m.t, t, rtol=0, atol=1e-12)
    assert m.t.shape == (101,) and m.t.dtype == np.float64
    assert set(m.positions) == {2} and set(m.velocities) == {2}
    assert m.positions[2].shape == (101, 3)
    np.testing.assert_allclose(m.positions[2][:, 0], x, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(m.positions[2][:, 1], 0.0)
    np.testing.assert_array_equal(m.positions[2][:, 2], -70.0)
    assert m.velocities[2] is not None and m.velocities[2].shape == (101, 3)
    np.testing.assert_allclose(m.velocities[2][:, 0], vx, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(m.velocities[2][:, 1:], 0.0)
    assert m.positions[2][0, 0] == -5.2
    assert m.velocities[2][0, 0] == pytest.approx(np.pi, abs=1e-9)


def test_arrays_are_read_only(tmp_path):
    path, _ = _good_csv(tmp_path)
    m = read_motion(path, [2])
    with pytest.raises(ValueError):
        m.t[0] = 1.0
    with pytest.raises(ValueError):
        m.positions[2][0, 0] = 1.0


def test_without_velocities_two_points_any_column_order(tmp_path):
    text = (
        "P3_z, P3_y ,P3_x,t,P2_x,P2_y,P2_z\n"
        "# a comment line\n"
        "-9,0.5,1,0.0,10,20,-30\n"
        "\n"
        "-8,0.25,2,0.5,11,21,-31\n"
        "-7,0,3,1.5,12,22,-32\n"
    )
    m = read_motion(_write(tmp_path, text), (2, 3))
    np.testing.assert_array_equal(m.t, [0.0, 0.5, 1.5])
    np.testing.assert_array_equal(m.positions[2], [[10, 20, -30], [11, 21, -31], [12, 22, -32]])
    np.testing.assert_array_equal(m.positions[3], [[1, 0.5, -9], [2, 0.25, -8], [3, 0, -7]])
    assert m.velocities == {2: None, 3: None}


def test_mixed_velocity_presence(tmp_path):
    text = "t,P1_x,P1_y,P1_z,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz\n0,0,0,0,1,1,1,2,3,4\n1,0,0,0,1,1,1,5,6,7\n"
    m = read_motion(_write(tmp_path, text), [1, 2])
    assert m.velocities[1] is None
    np.testing.assert_array_equal(m.velocities[2], [[2, 3, 4], [5, 6, 7]])


def test_extra_columns_warn(tmp_path):
    text = "t,P2_x,P2_y,P2_z,P9_x,comment_col\n0,1,2,3,4,5\n1,1,2,3,4,5\n"
    with pytest.warns(InputWarning, match="P9_x, comment_col"):
        m = read_motion(_write(tmp_path, text), [2])
    np.testing.assert_array_equal(m.positions[2], [[1, 2, 3], [1, 2, 3]])


def test_unrequested_point_velocities_warn(tmp_path):
    text = "t,P2_x,P2_y,P2_z,P3_vx\n0,1,2,3,4\n1,1,2,3,4\n"
    with pytest.warns(InputWarning, match="P3_vx"):
        read_motion(_write(tmp_path, text), [2])


def test_case_insensitive_header(tmp_path):
    text = "T,p2_X,p2_y,P2_Z\n0,1,2,3\n1,4,5,6\n"
    m = read_motion(_write(tmp_path, text), [2])
    np.testing.assert_array_equal(m.positions[2], [[1, 2, 3], [4, 5, 6]])


# ----------------------------------------------------------------------------
# errors
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n"])
def test_empty_file(tmp_path, text):
    _raises(_write(tmp_path, text), [2], "empty")


def test_missing_t(tmp_path):
    _raises(_write(tmp_path, "time,P2_x,P2_y,P2_z\n0,1,2,3\n1,1,2,3\n"), [2], ":1:", "'t'", "time, P2_x")


def test_missing_point_column_lists_missing_and_found(tmp_path):
    msg = _raises(
        _write(tmp_path, "t,P2_x,P2_z\n0,1,3\n1,1,3\n"), [2], ":1:", "P2_y", "found columns: t, P2_x, P2_z"
    )
    assert "P2_x," not in msg.split("found")[0]  # only the missing one is listed as missing


def test_missing_point_entirely(tmp_path):
    _raises(_write(tmp_path, HEADER3 + "0,1,2,3\n1,1,2,3\n"), [2, 5], "P5_x, P5_y, P5_z", "found columns")


@pytest.mark.parametrize(
    "vel, present, absent",
    [("P2_vx", "P2_vx", "P2_vy, P2_vz"), ("P2_vx,P2_vz", "P2_vx, P2_vz", "P2_vy")],
)
def test_partial_velocity_triplet(tmp_path, vel, present, absent):
    n = vel.count(",") + 1
    text = f"t,P2_x,P2_y,P2_z,{vel}\n0,1,2,3{',0' * n}\n1,1,2,3{',0' * n}\n"
    _raises(_write(tmp_path, text), [2], ":1:", present, f"not {absent}")


def test_duplicate_column(tmp_path):
    _raises(_write(tmp_path, "t,P2_x,P2_y,P2_z,P2_x\n0,1,2,3,1\n1,1,2,3,1\n"), [2], ":1:", "'P2_x'", "twice")


@pytest.mark.parametrize("cell", ["abc", "1.2.3", "", "1,5"])
def test_non_numeric_cell(tmp_path, cell):
    value = f'"{cell}"' if "," in cell else cell
    text = HEADER3 + "0,1,2,3\n" + f"0.5,1,{value},3\n" + "1,1,2,3\n"
    _raises(_write(tmp_path, text), [2], ":3:", "data row 2", "'P2_y'", repr(cell), "not a number")


@pytest.mark.parametrize("cell", ["nan", "NaN", "inf", "-inf", "1e999"])
def test_non_finite_cell(tmp_path, cell):
    text = HEADER3 + "0,1,2,3\n0.5,1,2,3\n" + f"1,1,2,{cell}\n"
    _raises(_write(tmp_path, text), [2], ":4:", "data row 3", "'P2_z'", repr(cell), "finite")


def test_non_finite_time(tmp_path):
    _raises(_write(tmp_path, HEADER3 + "0,1,2,3\nnan,1,2,3\n"), [2], ":3:", "'t'", "'nan'", "finite")


def test_ragged_row(tmp_path):
    _raises(_write(tmp_path, HEADER3 + "0,1,2,3\n1,1,2\n"), [2], ":3:", "3 cells", "expected 4")


@pytest.mark.parametrize("body", ["", "0,1,2,3\n"])
def test_fewer_than_two_rows(tmp_path, body):
    _raises(_write(tmp_path, HEADER3 + body), [2], "at least 2")


@pytest.mark.parametrize(
    "times, line, now, before",
    [
        (["0", "0.5", "0.5", "1"], 4, "0.5", "0.5"),  # repeated time
        (["0", "0.5", "0.25", "1"], 4, "0.25", "0.5"),  # going back
        (["1", "0", "2", "3"], 3, "0", "1"),
    ],
)
def test_times_not_strictly_increasing(tmp_path, times, line, now, before):
    text = HEADER3 + "".join(f"{t},1,2,3\n" for t in times)
    msg = _raises(_write(tmp_path, text), [2], f":{line}:", f"'t' = {now} s", f"previous time {before} s")
    assert "strictly increasing" in msg


def test_point_ids_must_be_integers(tmp_path):
    path, _ = _good_csv(tmp_path)
    with pytest.raises(TypeError):
        read_motion(path, ["2"])  # type: ignore[list-item]
