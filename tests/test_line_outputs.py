"""MoorDyn's ``LineOutputs`` flags in ``moorjax simulate``'s CSV and netCDF.

The bundled taut polyester example (one line, its fairlead surging 2 m over
8 s) with ``LineOutputs = pvUtcsdDK`` for 0.5 s at 6 segments (one run, ~60 s
with its compilation):

- the reader warns about ``D`` and ``K`` by name, and about characters that are
  no MoorDyn flag;
- the CSV gets MoorDyn's channels behind the line id (``L1_Node0_px`` …
  ``L1_Seg6_dSt``), the netCDF the same quantities;
- they hold physics: end nodes at the anchor and the fairlead, strain of the
  node positions, elastic tension EA·ε, damping force BA·ε̇ along the segment,
  strain rate the time derivative of the strain, velocity that of the position;
- a line asking for nothing gets no column.
"""

from __future__ import annotations

import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from moorjax.cli import main
from moorjax.examples import example_path
from moorjax.io import parse_deck, read_results
from moorjax.io.results import write_results
from moorjax.io.errors import InputWarning
from moorjax.io.line_outputs import split_flags

FLAGS = "pvUtcsdDK"
N = 6


def test_split_flags():
    assert split_flags("-") == ("", "", "")
    assert split_flags("tpT") == ("pt", "", "T")
    assert split_flags("pvUtcsdDKVb") == ("pvUtcsd", "DKVb", "")


def test_reader_names_flags_it_does_not_write():
    text = Path(example_path("taut_polyester")).read_text().replace(
        "1  main  1  2  110.0  160  -", "1  main  1  2  110.0  160  pDKx")
    with pytest.warns(InputWarning) as rec:
        parse_deck(text, "d.dat")
    msgs = [str(w.message) for w in rec]
    assert any(re.search(r"d\.dat:31: LINES id 1: LineOutputs = 'pDKx': D \(hydrodynamic drag force at "
                         r"each node\), K \(curvature at each node\) not written by moorjax", m)
               for m in msgs), msgs
    assert any("'x' not a MoorDyn line output flag" in m for m in msgs), msgs


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lo")
    deck = folder / "deck.dat"
    deck.write_text(Path(example_path("taut_polyester")).read_text().replace(
        "1  main  1  2  110.0  160  -", f"1  main  1  2  110.0  160  {FLAGS}"))
    motion = folder / "motion.csv"
    shutil.copy(Path(example_path("taut_polyester")).with_name("taut_polyester_motion.csv"), motion)
    nc = folder / "out.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["simulate", str(deck), "--duration", "0.5", "--segments", str(N), "--dt-out", "0.002",
                   "--motion", str(motion), "--out", str(nc), "--quiet"])
    assert rc == 0
    csv = folder / "out.csv"
    write_results(read_results(nc), csv)  # the CSV of the same dataset
    return dict(nc=nc, csv=csv)


def _csv(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", comments="#", skiprows=1)


@pytest.mark.slow
def test_csv_columns_are_moordyns_channels(run):
    header, data = _csv(run["csv"])
    expect = ([f"L1_Node{i}_p{c}" for i in range(N + 1) for c in "xyz"]
              + [f"L1_Node{i}_v{c}" for i in range(N + 1) for c in "xyz"]
              + [f"L1_Node{i}_U{c}" for i in range(N + 1) for c in "xyz"]
              + [f"L1_Seg{i}_Te" for i in range(1, N + 1)]
              + [f"L1_Seg{i}_c{c}" for i in range(1, N + 1) for c in "xyz"]
              + [f"L1_Seg{i}_St" for i in range(1, N + 1)]
              + [f"L1_Seg{i}_dSt" for i in range(1, N + 1)])
    assert header[-len(expect):] == expect
    assert header[: -len(expect)] == ["t", "L1_tension_a", "L1_tension_b", "P2_Fx", "P2_Fy", "P2_Fz"]
    assert np.all(np.isfinite(data))


@pytest.mark.slow
def test_line_outputs_hold_physics(run):
    ds = read_results(run["nc"])
    assert str(ds["line_outputs"].values[0]) == "pvUtcsd"
    t = ds["time"].values
    r = ds["node_position"].values[:, 0]
    v = ds["node_velocity"].values[:, 0]
    strain = ds["segment_strain"].values[:, 0]
    rate = ds["segment_strain_rate"].values[:, 0]
    tension = ds["segment_elastic_tension"].values[:, 0]
    damping = ds["segment_damping_force"].values[:, 0]
    assert np.ptp(r[:, -1, 0]) > 0.1  # the fairlead moves
    l0 = 110.0 / N
    seg = r[:, 1:] - r[:, :-1]
    np.testing.assert_allclose(strain, np.linalg.norm(seg, axis=-1) / l0 - 1.0, rtol=1e-10)
    # the deck's linear EA and BA [N·s]
    text = Path(example_path("taut_polyester")).read_text().splitlines()
    row = next(ln.split() for ln in text if ln.startswith("main"))
    ea, ba = float(row[3]), float(row[4])
    np.testing.assert_allclose(tension, ea * strain, rtol=1e-9)
    unit = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
    np.testing.assert_allclose(damping, (ba * rate)[..., None] * unit, rtol=1e-9, atol=1e-6)
    # time derivatives (central differences of the 0.01 s outputs)
    dt = t[2:] - t[:-2]
    np.testing.assert_allclose(rate[1:-1], (strain[2:] - strain[:-2]) / dt[:, None],
                               atol=0.05 * np.abs(rate).max())
    np.testing.assert_allclose(v[1:-1], (r[2:] - r[:-2]) / dt[:, None, None],
                               atol=0.05 * np.abs(v).max())
    assert np.all(ds["node_water_velocity"].values == 0.0)  # no current in the deck
    # the CSV holds the same numbers
    header, data = _csv(run["csv"])
    k = header.index("L1_Seg3_Te")
    np.testing.assert_allclose(data[:, k], tension[:, 2], rtol=1e-12)
