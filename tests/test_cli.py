"""The ``moorjax`` command line: ``statics`` on bundled and user decks, bad input,
``examples``.

``cmd_statics`` solves each line eagerly, so each line costs one compilation; the
decks here are kept to the few lines that the checks need.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from moorpy.Catenary import catenary as moorpy_catenary

from moorjax.cli import main
from moorjax.examples import EXAMPLES, example_path

RHO, G = 1025.0, 9.80665
CASE_A = dict(tension_b=911089.02, tension_a=736938.85, grounded=134.78553)  # MoorPy
KEYS = {"id", "tension_a", "tension_b", "force_a", "force_b", "grounded_length"}


def run_json(capsys, *argv):
    rc = main(["statics", *argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    rows = json.loads(out)
    assert isinstance(rows, list)
    return rows


# ------------------------------------------------------------ bundled example


def test_statics_example_json(capsys):
    rows = run_json(capsys, "example:oc3_catenary", "--segments", "40")
    assert len(rows) == 1
    row = rows[0]
    assert KEYS <= set(row), set(row)
    assert row["id"] == 1
    fa, fb = np.asarray(row["force_a"]), np.asarray(row["force_b"])
    assert fa.shape == fb.shape == (3,)
    assert row["tension_b"] == pytest.approx(float(np.linalg.norm(fb)), rel=1e-12)
    assert row["tension_a"] == pytest.approx(float(np.linalg.norm(fa)), rel=1e-12)
    # within 0.1 % of MoorPy at 40 segments
    assert row["tension_b"] == pytest.approx(CASE_A["tension_b"], rel=1e-3)
    assert row["tension_a"] == pytest.approx(CASE_A["tension_a"], rel=1e-3)
    assert row["grounded_length"] == pytest.approx(CASE_A["grounded"], abs=2.0)
    # the line pulls the fairlead (x = -5.2) down and towards the anchor (x = -853.87),
    # and the anchor towards the fairlead; no friction: horizontal forces balance
    assert fb[0] < 0 and fb[2] < 0 and fa[0] > 0
    assert fb[1] == 0.0 and fa[1] == 0.0
    assert fa[0] + fb[0] == pytest.approx(0.0, abs=1e-6 * row["tension_b"])
    if "n_segments" in row:
        assert row["n_segments"] == 40


def test_examples_lists_both(capsys):
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    for name in ("oc3_catenary", "taut_polyester"):
        assert f"example:{name}" in out
        assert Path(example_path(name)).is_file()
    assert set(EXAMPLES) == {"oc3_catenary", "taut_polyester"}
    assert len([ln for ln in out.splitlines() if ln.startswith("example:")]) == len(EXAMPLES)


# ------------------------------------------------------------ a user deck

# fairleads on a 5 m radius at z = -10 m, three azimuths; anchors on the seabed (150 m)
DEPTH = 150.0
USER_TYPES = {
    # name: (diameter m, mass kg/m, EA N)
    "chain": (0.10, 60.0, 6.0e8),
    "heavy": (0.20, 200.0, 2.0e9),
    "poly": (0.15, 15.0, 1.5e8),  # buoyant: 15 < 1025·π·0.15²/4 ≈ 18.1 kg/m
}
USER_LINES = [
    # (id, type, azimuth deg, horizontal span XF m, unstretched length m)
    (1, "chain", 0.0, 415.0, 450.0),  # catenary, partly grounded
    (2, "heavy", 120.0, 345.0, 400.0),  # heavy chain, partly grounded
    (3, "poly", 240.0, 145.0, 201.0),  # taut
]
FAIRLEAD_R, FAIRLEAD_Z = 5.0, -10.0


def _user_geometry():
    pts = []
    for lid, _, az, xf, _ in USER_LINES:
        u = np.array([math.cos(math.radians(az)), math.sin(math.radians(az)), 0.0])
        fair = FAIRLEAD_R * u + np.array([0.0, 0.0, FAIRLEAD_Z])
        anchor = (FAIRLEAD_R + xf) * u + np.array([0.0, 0.0, -DEPTH])
        pts.append((lid, anchor, fair))
    return pts


def _xyz(p):
    return " ".join(repr(float(c)) for c in p)


def user_deck_text(diameter_override=None):
    rows = [
        "MoorDyn v2 input file: a user deck for the moorjax CLI tests",
        "three lines: catenary chain, heavy chain, taut buoyant polyester",
        "----------------------- LINE TYPES ------------------------------------------",
        "TypeName   Diam    Mass/m     EA         BA/-zeta    EI    Cd     Ca     CdAx    CaAx",
        "(name)     (m)     (kg/m)     (N)        (N-s/-)     (N-m^2) (-)  (-)    (-)     (-)",
    ]
    for name, (d, m, ea) in USER_TYPES.items():
        if diameter_override is not None and name == "heavy":
            d = diameter_override
        rows.append(f"{name}  {d}  {m}  {ea}  -0.8  0.0  1.2  1.0  0.2  0.0")
    rows += [
        "---------------------- POINTS --------------------------------",
        "ID    Attachment  X       Y       Z       Mass   Volume  CdA    Ca",
        "(#)   (-)       (m)     (m)     (m)     (kg)   (m^3)   (m^2)  (-)",
    ]
    pid = 0
    line_rows = []
    for (lid, anchor, fair), (_, tname, _, _, length) in zip(_user_geometry(), USER_LINES):
        pa, pb = pid + 1, pid + 2
        pid += 2
        rows.append(f"{pa}  Fixed  {_xyz(anchor)}  0 0 0 0")
        rows.append(f"{pb}  Coupled  {_xyz(fair)}  0 0 0 0")
        line_rows.append(f"{lid}  {tname}  {pa}  {pb}  {length}  20  -")
    rows += [
        "---------------------- LINES ----------------------------------------",
        "ID   LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs",
        "(#)   (name)     (#)      (#)       (m)       (-)     (-)",
        *line_rows,
        "---------------------- OPTIONS -----------------------------------------",
        "9.80665                  g                    gravity (m/s^2)",
        "1025.0                   rho                  water density (kg/m^3)",
        f"{DEPTH}                    WtrDpth              water depth (m)",
        "3000000.0                kBot                 seabed stiffness (Pa/m)",
        "300000.0                 cBot                 seabed damping (Pa-s/m)",
        "------------------------- need this line --------------------------------------",
    ]
    return "\n".join(rows) + "\n"


def moorpy_line(tname, xf, length):
    d, m, ea = USER_TYPES[tname]
    w = (m - RHO * math.pi * d * d / 4) * G
    fah, fav, fbh, fbv, info = moorpy_catenary(
        xf, FAIRLEAD_Z + DEPTH, length, ea, w, CB=0.0, Tol=1e-10, MaxIter=200
    )
    return math.hypot(fah, fav), math.hypot(fbh, fbv), info["LBot"], w


def test_statics_user_deck_matches_moorpy(tmp_path, capsys):
    deck = tmp_path / "three_lines.dat"
    deck.write_text(user_deck_text())
    rows = run_json(capsys, str(deck), "--segments", "80")
    assert [r["id"] for r in rows] == [1, 2, 3]
    geometry = {lid: (anchor, fair) for lid, anchor, fair in _user_geometry()}
    regimes = {}
    for row, (lid, tname, az, xf, length) in zip(rows, USER_LINES):
        ta, tb, lbot, w = moorpy_line(tname, xf, length)
        assert row["tension_b"] == pytest.approx(tb, rel=5e-4), (lid, row["tension_b"], tb)
        assert row["tension_a"] == pytest.approx(ta, rel=5e-4), (lid, row["tension_a"], ta)
        assert row["grounded_length"] == pytest.approx(lbot, abs=1.0), lid
        assert row["tension_b"] == pytest.approx(float(np.linalg.norm(row["force_b"])), rel=1e-12)
        # the horizontal pull on the fairlead points at this line's own anchor
        anchor, fair = geometry[lid]
        fb = np.asarray(row["force_b"])
        towards = (anchor - fair)[:2] / np.linalg.norm((anchor - fair)[:2])
        assert fb[:2] @ towards == pytest.approx(np.linalg.norm(fb[:2]), rel=1e-9)
        regimes[lid] = (lbot, w)
    # the deck really exercises three regimes
    assert regimes[1][0] > 0 and regimes[2][0] > 0 and regimes[3][0] == 0
    assert regimes[3][1] < 0 < regimes[1][1] < regimes[2][1]


# ------------------------------------------------------------ bad input


def test_negative_diameter_exit_code_2(tmp_path, capsys):
    deck = tmp_path / "bad.dat"
    deck.write_text(user_deck_text(diameter_override=-0.2))
    rc = main(["statics", str(deck), "--json"])
    out, err = capsys.readouterr()
    assert rc == 2
    assert out == ""
    assert "Diam" in err and "-0.2" in err and "heavy" in err, err
    assert "bad.dat" in err


def test_missing_file_exit_code_2(tmp_path, capsys):
    missing = tmp_path / "nope" / "deck.dat"
    rc = main(["statics", str(missing)])
    out, err = capsys.readouterr()
    assert rc == 2
    assert out == ""
    assert "deck.dat" in err and "No such file" in err, err


def test_unknown_example_exit_code_2(capsys):
    rc = main(["statics", "example:no_such_deck"])
    err = capsys.readouterr().err
    assert rc == 2
    assert "no_such_deck" in err and "oc3_catenary" in err


def test_fairlead_below_seabed_exit_code_2(tmp_path, capsys):
    text = user_deck_text().replace(f"{FAIRLEAD_Z!r}  0 0 0 0", "-160.0  0 0 0 0", 1)
    assert "-160.0" in text
    deck = tmp_path / "below.dat"
    deck.write_text(text)
    rc = main(["statics", str(deck)])
    out, err = capsys.readouterr()
    assert rc == 2
    assert "below" in err and "seabed" in err, err


@pytest.mark.parametrize("segments", ["0", "-3", "ten"])
def test_bad_segments_rejected_by_parser(capsys, segments):
    with pytest.raises(SystemExit) as info:
        main(["statics", "example:oc3_catenary", "--segments", segments])
    assert info.value.code == 2
    assert "positive integer" in capsys.readouterr().err


def test_statics_method_auto_is_the_exact_catenary_and_fem_the_discrete_model(capsys):
    """``--method auto`` (default) reports the exact catenary where it applies, at any
    segment count; ``--method fem`` the finite-element equilibrium a simulation starts
    from, whose error against MoorPy falls with the segment count."""
    (auto,) = run_json(capsys, "example:oc3_catenary", "--segments", "10")
    (fem,) = run_json(capsys, "example:oc3_catenary", "--segments", "10", "--method", "fem")
    assert auto["method"] == "catenary" and fem["method"] == "fem"
    assert auto["tension_b"] == pytest.approx(CASE_A["tension_b"], rel=1e-6)
    assert auto["tension_a"] == pytest.approx(CASE_A["tension_a"], rel=1e-6)
    assert auto["grounded_length"] == pytest.approx(CASE_A["grounded"], abs=1e-3)
    err = abs(fem["tension_b"] / CASE_A["tension_b"] - 1)
    assert 1e-5 < err < 2e-2  # 10 segments: a visible discretisation error


def test_statics_method_catenary_is_refused_where_it_cannot_hold(capsys):
    """``--method catenary`` on a line in a current, or on a deck with a free point (a
    system), exits with code 2 and says what to use instead."""
    data = Path(__file__).parent / "data"
    for deck, why in ((data / "current_steady" / "line.dat", "no current"),
                      (data / "moorpy_case2.dat", "solved as a system")):
        rc = main(["statics", str(deck), "--method", "catenary"])
        err = capsys.readouterr().err
        assert rc == 2 and why in err and "auto" in err, err


def test_building_the_parser_leaves_the_fitting_machinery_unloaded():
    """Every command builds the whole parser, ``fit``'s included; only ``moorjax
    fit`` itself loads optax and moorjax.identify (a fresh interpreter: this
    one's tests may have loaded them)."""
    import subprocess
    import sys

    probe = ("import sys; from moorjax.cli import build_parser; build_parser(); "
             "print(sorted(m for m in ('optax', 'moorjax.identify') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
