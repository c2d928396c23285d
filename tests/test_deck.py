"""Tests for moorjax.io.deck: the MoorDyn v2 deck reader (pure Python, no JAX)."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from moorjax.io.deck import (
    Deck,
    DeckLine,
    DeckLineType,
    DeckPoint,
    options_with_defaults,
    parse_deck,
    read_deck,
)
from moorjax.io.errors import InputError, InputWarning

DATA = Path(__file__).parent / "data"
CASE_A = DATA / "case_A.dat"
CASE_B = DATA / "case_B.dat"

# line numbers (1-based) of the rows in case_A.dat / case_B.dat
TYPE_ROW, POINT1_ROW, POINT2_ROW, LINE_ROW = 22, 26, 27, 31
TYPES_HDR, POINTS_HDR, LINES_HDR, OPTIONS_HDR, END_ROW = 19, 23, 28, 32, 47


def _lines_A() -> list[str]:
    return CASE_A.read_text().splitlines()


def _write(tmp_path: Path, lines: list[str], name: str = "case.dat") -> Path:
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return p


def _mutate(tmp_path: Path, replacements: dict[int, str | list[str]]) -> Path:
    """case_A with the given 1-based lines replaced (a list inserts several lines)."""
    lines = _lines_A()
    for lineno in sorted(replacements, reverse=True):
        new = replacements[lineno]
        lines[lineno - 1 : lineno] = new if isinstance(new, list) else [new]
    return _write(tmp_path, lines)


def _raises(path: Path, *fragments: str) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        with pytest.raises(InputError) as info:
            read_deck(path)
    msg = str(info.value)
    for f in fragments:
        assert f in msg, f"{f!r} not in {msg!r}"
    return msg


# ----------------------------------------------------------------------------
# the two reference decks
# ----------------------------------------------------------------------------


COMMON_OPTIONS = {
    "writeLog": 0.0,
    "tScheme": "rk4",
    "g": 9.80665,
    "rho": 1025.0,
    "kBot": 3.0e6,
    "cBot": 3.0e5,
    "FrictionCoefficient": 0.0,
    "dtIC": 1.0,
    "TmaxIC": 600.0,
    "threshIC": 1e-6,
    "disableOutput": 1.0,
    "disableOutTime": 1.0,
}


def test_case_A_every_value():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean deck emits no warning
        deck = read_deck(CASE_A)
    assert isinstance(deck, Deck)
    assert deck.path == str(CASE_A)
    assert deck.title.splitlines()[0] == "MoorDyn v2 input file (tested with MoorDyn 2.7.2 from PyPI)"
    assert deck.title.splitlines()[1] == "Case A: OC3-like catenary, surge 5 m / 10 s."
    assert len(deck.title.splitlines()) == 18
    assert deck.line_types == {
        "main": DeckLineType(
            name="main",
            diameter=0.09,
            mass_per_length=77.7066,
            ea=384243000.0,
            ea_table=None,
            ba=6236000.0,
            ei=0.0,
            cd=1.6,
            ca=1.0,
            cd_axial=0.1,
            ca_axial=0.0,
            source_line=TYPE_ROW,
        )
    }
    assert deck.points == {
        1: DeckPoint(1, "fixed", (-853.87, 0.0, -320.0), 0.0, 0.0, 0.0, 0.0, POINT1_ROW),
        2: DeckPoint(2, "coupled", (-5.2, 0.0, -70.0), 0.0, 0.0, 0.0, 0.0, POINT2_ROW),
    }
    assert deck.lines == (DeckLine(1, "main", 1, 2, 902.2, 160, "-", LINE_ROW),)
    assert deck.options == {**COMMON_OPTIONS, "dtM": 3.3333333333333335e-05, "WtrDpth": 320.0}
    assert list(deck.options) == [
        "writeLog", "dtM", "tScheme", "g", "rho", "WtrDpth", "kBot", "cBot",
        "FrictionCoefficient", "dtIC", "TmaxIC", "threshIC", "disableOutput", "disableOutTime",
    ]  # fmt: skip
    assert deck.warnings == ()
    assert isinstance(deck.lines[0].n_segments, int)


def test_case_B_every_value():
    deck = read_deck(str(CASE_B))
    assert deck.path == str(CASE_B)
    assert "Case B: taut buoyant polyester-like line" in deck.title
    assert deck.line_types == {
        "main": DeckLineType(
            "main", 0.12, 10.8, 150000000.0, None, 177100.0, 0.0, 1.6, 1.0, 0.05, 0.0, TYPE_ROW
        )
    }
    assert deck.points == {
        1: DeckPoint(1, "fixed", (-80.5168, 0.0, -80.0), 0.0, 0.0, 0.0, 0.0, POINT1_ROW),
        2: DeckPoint(2, "coupled", (0.0, 0.0, -5.0), 0.0, 0.0, 0.0, 0.0, POINT2_ROW),
    }
    assert deck.lines == (DeckLine(1, "main", 1, 2, 110.0, 160, "-", LINE_ROW),)
    assert deck.options == {**COMMON_OPTIONS, "dtM": 1e-05, "WtrDpth": 80.0}
    assert deck.warnings == ()


def test_parse_deck_equals_read_deck():
    text = CASE_A.read_text()
    assert parse_deck(text, str(CASE_A)) == read_deck(CASE_A)
    assert parse_deck(text).path == "<string>"


def test_dataclasses_are_frozen():
    deck = read_deck(CASE_A)
    with pytest.raises(AttributeError):
        deck.lines[0].length = 1.0  # type: ignore[misc]
    with pytest.raises(AttributeError):
        deck.points[1].position = (0.0, 0.0, 0.0)  # type: ignore[misc]


def test_options_with_defaults_case_A():
    opts = options_with_defaults(read_deck(CASE_A))
    # given in the deck
    assert opts["dtM"] == 3.3333333333333335e-05
    assert opts["tScheme"] == "rk4"
    assert opts["WtrDpth"] == 320.0
    assert opts["TmaxIC"] == 600.0
    # MoorDyn-C v2 defaults
    assert opts["CdScaleIC"] == 5.0
    assert opts["CFL"] == 0.5
    assert opts["FricDamp"] == 200.0
    assert opts["StatDynFricScale"] == 1.0
    assert opts["WaveKin"] == 0.0 and opts["Currents"] == 0.0


def test_options_with_defaults_empty_options(tmp_path):
    lines = _lines_A()[: OPTIONS_HDR - 1]  # drop the whole OPTIONS section
    with pytest.warns(InputWarning, match="WtrDpth not given"):
        deck = read_deck(_write(tmp_path, lines))
    assert deck.options == {}
    opts = options_with_defaults(deck)
    assert opts["g"] == 9.80665
    assert opts["rho"] == 1025.0
    assert opts["kBot"] == 3.0e6
    assert opts["cBot"] == 3.0e5
    assert opts["tScheme"] == "rk2"
    assert opts["FrictionCoefficient"] == 0.0
    assert opts["dtM"] is None  # MoorDyn-C derives the step from CFL
    assert opts["dtIC"] == 1.0 and opts["TmaxIC"] == 120.0 and opts["threshIC"] == 0.001
    # MoorDyn deepens the seabed to the lowest point when WtrDpth is not given
    assert opts["WtrDpth"] == 320.0


# ----------------------------------------------------------------------------
# accepted variants
# ----------------------------------------------------------------------------


def test_v1_section_names_aliases_comments_and_point_prefixes(tmp_path):
    text = """\
---------------------- MoorDyn Input File ------------------------
v1-style names, comments, P-prefixed attachments
------------------------- LINE DICTIONARY -------------------------
LineType  Diam  MassDen  EA  BA/-zeta  EI  Cd  Ca  CdAx  CaAx
(-)       (m)   (kg/m)   (N) (N-s)     (-) (-) (-) (-)   (-)
chain  0.1  150.0  1e8  -1.0  0  2.3  1  1.0  0.5   ! a comment
-------------------- CONNECTION PROPERTIES ------------------------
Node  Type  X  Y  Z  M  V  FX  FY  FZ  CdA  CA
(-)   (-)   (m) (m) (m) (kg) (m^3) (kN) (kN) (kN) (m^2) (-)
1   Anchor  -500  0  -150  0  0  0  0  0  0  0
2   Vessel   0    0   -9   0  0  0  0  0  0  0

3   fix     -400  0  -150  0  0  0  0  0  0  0   # third point
---------------------- LINE PROPERTIES ----------------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  Outputs
(-)  (-)  (-)  (-)  (m)  (-)  (-)
1  chain  P1  p2  520.0  20  pt
2  chain  point3  2  420.0  20.0  -
---------------------- SOLVER OPTIONS -----------------------------
150   WtrDpth
3e6   kb      - bottom stiffness
3e5   cb
1020  rhoW
5.0   ICDfac
0.01  ICthresh
RK4   tScheme
"""
    deck = parse_deck(text, str(tmp_path / "v1.dat"))
    assert deck.title == (
        "---------------------- MoorDyn Input File ------------------------\n"
        "v1-style names, comments, P-prefixed attachments"
    )
    assert deck.line_types["chain"].ba == -1.0  # -zeta kept as given
    assert deck.line_types["chain"].cd_axial == 1.0 and deck.line_types["chain"].ca_axial == 0.5
    assert [p.attachment for p in deck.points.values()] == ["fixed", "coupled", "fixed"]
    assert deck.points[3].position == (-400.0, 0.0, -150.0)
    assert deck.points[3].source_line == 13
    assert [(ln.point_a, ln.point_b, ln.n_segments) for ln in deck.lines] == [(1, 2, 20), (3, 2, 20)]
    assert deck.lines[0].outputs == "pt"
    assert deck.options == {
        "WtrDpth": 150.0,
        "kBot": 3e6,
        "cBot": 3e5,
        "rho": 1020.0,
        "CdScaleIC": 5.0,
        "threshIC": 0.01,
        "tScheme": "rk4",
    }
    assert deck.warnings == ()


def test_tabulated_ea(tmp_path, monkeypatch):
    sub = tmp_path / "deck"
    sub.mkdir()
    (sub / "poly_ea.txt").write_text(
        "----Polyester----\nStrain    Tension\n(-)       (N)\n0.0 0.0\n0.01 1.5e6\n0.02 4.0e6\n0.05 1.2e7\n"
    )
    lines = _lines_A()
    lines[TYPE_ROW - 1] = "main  0.09  77.7066  poly_ea.txt  -0.8  0.0  1.6  1.0  0.1  0.0"
    deck_path = _write(sub, lines)
    monkeypatch.chdir(tmp_path)  # the table is found next to the deck, not in the cwd
    deck = read_deck(deck_path)
    lt = deck.line_types["main"]
    assert lt.ea is None
    assert lt.ea_table == ((0.0, 0.0), (0.01, 1.5e6), (0.02, 4.0e6), (0.05, 1.2e7))
    assert lt.ba == -0.8


@pytest.mark.parametrize(
    "table, fragments",
    [
        ("S T\n(-) (N)\n0 0\n0.02 1e6\n0.01 2e6\n", ["poly_ea.txt:5", "0.01", "strictly increasing"]),
        ("S T\n(-) (N)\n0 0\n0.01 1e6\n0.01 2e6\n", ["poly_ea.txt:5", "strictly increasing"]),
        ("S T\n(-) (N)\n0 -5\n0.01 1e6\n", ["poly_ea.txt:3", "-5", ">= 0"]),
        ("S T\n(-) (N)\n0 0\n0.01 nan\n", ["poly_ea.txt:4", "nan", "finite"]),
        ("S T\n(-) (N)\n0 0\n0.01 abc\n", ["poly_ea.txt:4", "abc"]),
        ("S T\n(-) (N)\n0 0\n", ["poly_ea.txt", "at least 2"]),
    ],
)
def test_tabulated_ea_errors(tmp_path, table, fragments):
    (tmp_path / "poly_ea.txt").write_text(table)
    deck = _mutate(tmp_path, {TYPE_ROW: "main  0.09  77.7066  poly_ea.txt  -0.8  0.0  1.6  1.0  0.1  0.0"})
    msg = _raises(deck, *fragments)
    assert f"case.dat:{TYPE_ROW}" in msg  # also names the deck row that refers to the table


def test_tabulated_ea_missing_file(tmp_path):
    deck = _mutate(tmp_path, {TYPE_ROW: "main  0.09  77.7066  nothere.txt  -0.8  0.0  1.6  1.0  0.1  0.0"})
    _raises(deck, f"case.dat:{TYPE_ROW}:", "'nothere.txt'", "EA")


# ----------------------------------------------------------------------------
# errors: file:line, field, value, unit, expectation
# ----------------------------------------------------------------------------


def test_error_message_format(tmp_path):
    deck = _mutate(tmp_path, {TYPE_ROW: "main  -0.09  77.7066  384243000.0  6236000.0  0.0  1.6  1.0  0.1  0.0"})
    msg = _raises(deck)
    assert msg == f"{deck}:{TYPE_ROW}: LINE TYPES 'main': Diam = -0.09 m must be > 0"


T = TYPE_ROW
P1, P2, L = POINT1_ROW, POINT2_ROW, LINE_ROW
GOOD_TYPE = "main  0.09  77.7066  384243000.0  6236000.0  0.0  1.6  1.0  0.1  0.0"

ERROR_CASES = {
    # LINE TYPES
    "type too few columns": ({T: "main  0.09  77.7066  384243000.0"}, T, ["columns", "BA/-zeta"]),
    "type diam not a number": ({T: GOOD_TYPE.replace("0.09", "abc")}, T, ["Diam", "'abc'", "not a number"]),
    "type diam zero": ({T: GOOD_TYPE.replace("0.09", "0.0")}, T, ["Diam = 0.0 m", "> 0"]),
    "type mass zero": ({T: GOOD_TYPE.replace("77.7066", "0")}, T, ["Mass/m = 0 kg/m", "> 0"]),
    "type mass negative": ({T: GOOD_TYPE.replace("77.7066", "-77.7")}, T, ["Mass/m = -77.7 kg/m", "> 0"]),
    "type ea negative": ({T: GOOD_TYPE.replace("384243000.0", "-3.8e8")}, T, ["EA = -3.8e8 N", "> 0"]),
    "type ea zero": ({T: GOOD_TYPE.replace("384243000.0", "0")}, T, ["EA = 0 N", "> 0"]),
    "type ea nan": ({T: GOOD_TYPE.replace("384243000.0", "nan")}, T, ["EA = nan N", "finite"]),
    "type ea inf": ({T: GOOD_TYPE.replace("384243000.0", "inf")}, T, ["EA = inf N", "finite"]),
    "type ea overflow": ({T: GOOD_TYPE.replace("384243000.0", "1e999")}, T, ["EA = 1e999 N", "finite"]),
    "type ba nan": ({T: GOOD_TYPE.replace("6236000.0", "NaN")}, T, ["BA/-zeta = NaN", "finite"]),
    "type ei negative": ({T: GOOD_TYPE.replace("6236000.0  0.0", "6236000.0  -5")}, T, ["EI = -5", ">= 0"]),
    "type cd negative": ({T: GOOD_TYPE.replace("1.6", "-1.6")}, T, ["Cd = -1.6", ">= 0"]),
    "type ca negative": ({T: GOOD_TYPE.replace("1.6  1.0", "1.6  -1.0")}, T, ["Ca = -1.0", ">= 0"]),
    "type cdax negative": ({T: GOOD_TYPE.replace("0.1  0.0", "-0.1  0.0")}, T, ["CdAx = -0.1", ">= 0"]),
    "type caax negative": ({T: GOOD_TYPE.replace("0.1  0.0", "0.1  -0.5")}, T, ["CaAx = -0.5", ">= 0"]),
    "type viscoelastic": ({T: GOOD_TYPE.replace("384243000.0", "1e8|2e8")}, T, ["'1e8|2e8'", "not supported"]),
    "duplicate type": ({T: [GOOD_TYPE, GOOD_TYPE.replace("0.09", "0.1")]}, T + 1, ["duplicate", "'main'", f"line {T}"]),
    # POINTS
    "point too few columns": ({P1: "1  Fixed  -853.87 0.0 -320.0"}, P1, ["columns", "Mass"]),
    "point x not a number": ({P1: "1  Fixed  -853.8x 0.0 -320.0  0 0 0 0"}, P1, ["X = '-853.8x'", "not a number"]),
    "point y inf": ({P1: "1  Fixed  -853.87 inf -320.0  0 0 0 0"}, P1, ["Y = inf m", "finite"]),
    "point id not integer": ({P1: "1.5  Fixed  -853.87 0.0 -320.0  0 0 0 0"}, P1, ["ID = '1.5'", "integer"]),
    "point negative mass": ({P1: "1  Fixed  -853.87 0.0 -320.0  -3 0 0 0"}, P1, ["Mass = -3 kg", ">= 0"]),
    "point negative volume": ({P1: "1  Fixed  -853.87 0.0 -320.0  0 -1 0 0"}, P1, ["Volume = -1 m^3", ">= 0"]),
    "duplicate point": ({P2: "1  Coupled -5.2 0.0 -70.0  0 0 0 0"}, P2, ["duplicate", "id 1", f"line {P1}"]),
    "point out of sequence": ({P2: "3  Coupled -5.2 0.0 -70.0  0 0 0 0"}, P2, ["id 3", "expected 2"]),
    "point below seabed": ({P1: "1  Fixed  -853.87 0.0 -400.0  0 0 0 0"}, P1, ["-400.0", "seabed", "320.0"]),
    "body point, no bodies": ({P2: "2  Body1 -5.2 0.0 -70.0  0 0 0 0"}, P2, ["'Body1'", "no body with id 1", "no BODIES"]),
    "body point without number": ({P2: "2  Body -5.2 0.0 -70.0  0 0 0 0"}, P2, ["'Body'", "Body<n>"]),
    "body point zero": ({P2: "2  Body0 -5.2 0.0 -70.0  0 0 0 0"}, P2, ["'Body0'", "Body<n>"]),
    "turbine point": ({P2: "2  Turbine3 -5.2 0.0 -70.0  0 0 0 0"}, P2, ["'Turbine3'", "not supported"]),
    "unknown point type": ({P2: "2  Floating -5.2 0.0 -70.0  0 0 0 0"}, P2, ["'Floating'", "Fixed"]),
    # LINES
    "line too few columns": ({L: "1  main  1  2  902.2"}, L, ["columns", "NumSegs"]),
    "line unknown type": ({L: "1  chain  1  2  902.2  160  -"}, L, ["'chain'", "LINE TYPES", "'main'"]),
    "line unknown point": ({L: "1  main  1  7  902.2  160  -"}, L, ["AttachB = '7'", "no point with id 7"]),
    "line unknown P point": ({L: "1  main  P9  2  902.2  160  -"}, L, ["AttachA = 'P9'", "id 9"]),
    "line same point": ({L: "1  main  2  P2  902.2  160  -"}, L, ["same point", "'2'", "'P2'"]),
    "line zero length": ({L: "1  main  1  2  0  160  -"}, L, ["UnstrLen = 0 m", "> 0"]),
    "line negative length": ({L: "1  main  1  2  -902.2  160  -"}, L, ["UnstrLen = -902.2 m", "> 0"]),
    "line nan length": ({L: "1  main  1  2  nan  160  -"}, L, ["UnstrLen = nan m", "finite"]),
    "line zero segments": ({L: "1  main  1  2  902.2  0  -"}, L, ["NumSegs = 0", "> 0"]),
    "line negative segments": ({L: "1  main  1  2  902.2  -4  -"}, L, ["NumSegs = -4", "> 0"]),
    "line fractional segments": ({L: "1  main  1  2  902.2  12.5  -"}, L, ["NumSegs = '12.5'", "integer"]),
    "line rod attachment": ({L: "1  main  R1A  2  902.2  160  -"}, L, ["'R1A'", "not supported"]),
    "line body attachment": ({L: "1  main  1  B1  902.2  160  -"}, L, ["'B1'", "names a point, not a body", "Body<n>"]),
    "line garbage attachment": ({L: "1  main  1  x2  902.2  160  -"}, L, ["'x2'", "point id"]),
    "duplicate line": ({L: ["1  main  1  2  902.2  160  -", "1  main  1  2  900.0  160  -"]}, L + 1, ["duplicate", "id 1"]),
    # OPTIONS
    "option not a number": ({38: "deep  WtrDpth"}, 38, ["WtrDpth", "'deep'"]),
    "option nan": ({36: "nan  g"}, 36, ["g = nan", "finite"]),
    "option negative kbot": ({39: "-3e6  kBot"}, 39, ["kBot = -3e6 Pa/m", ">= 0"]),
    "option zero depth": ({38: "0  WtrDpth"}, 38, ["WtrDpth = 0 m", "> 0"]),
    "option zero dtM": ({34: "0  dtM"}, 34, ["dtM = 0 s", "> 0"]),
    "option waves": ({33: ["0 writeLog", "5 WaveKin"]}, 34, ["WaveKin = 5", "not implemented in MoorDyn"]),
    "option seafloor file": ({33: ["0 writeLog", "bathy.txt SeafloorFile"]}, 34, ["'bathy.txt'", "no such file next to the deck"]),
    # structure
    "bodies row, unknown kind": (
        {POINTS_HDR: ["------ BODIES ------", "ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I Volume CdA Ca",
                  "(#) (-) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kg-m^2) (m^3) (m^2) (-)",
                  "1 floating 0 0 0 0 0 0 0 0 0 0 0 0", "---------------------- POINTS ----------------"]},
        P1, ["BODIES id 1", "'floating'", "Coupled"],
    ),
    "rods row": (
        {LINES_HDR: ["------ RODS ------", "ID RodType Attachment Xa Ya Za Xb Yb Zb NumSegs RodOutputs",
                 "(#) (name) (-) (m) (m) (m) (m) (m) (m) (-) (-)",
                 "1 Can Body1 0 0 2 0 0 15 8 p", "---------------------- LINES ----------------"]},
        L, ["RODS", "not supported"],
    ),
    "failure row": (
        {END_ROW: ["------ FAILURE ------", "FailureID Point Lines FailTime FailTen", "() () (,) (s) (N)",
                   "1 2 1 10 0", "---- need this line ----"]},
        END_ROW + 3, ["FAILURE", "not supported"],
    ),
    "second LINES section": (
        {OPTIONS_HDR: ["---------------------- LINES ----", "ID ...", "(#) ...", "2 main 1 2 900 10 -",
                       "---------------------- OPTIONS ----"]},
        OPTIONS_HDR, ["LINES", f"line {LINES_HDR}"],
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", list(ERROR_CASES), ids=list(ERROR_CASES))
def test_error_cases(tmp_path, case):
    replacements, lineno, fragments = ERROR_CASES[case]
    deck = _mutate(tmp_path, replacements)
    _raises(deck, f"case.dat:{lineno}:", *fragments)


def test_missing_lines_section(tmp_path):
    lines = _lines_A()
    del lines[LINES_HDR - 1 : OPTIONS_HDR - 1]
    _raises(_write(tmp_path, lines), "case.dat", "LINES", "missing")


def test_missing_line_types_section(tmp_path):
    lines = _lines_A()
    del lines[TYPES_HDR - 1 : POINTS_HDR - 1]
    _raises(_write(tmp_path, lines), "case.dat", "LINE TYPES", "missing")


def test_empty_lines_section(tmp_path):
    lines = _lines_A()
    del lines[LINE_ROW - 1]
    _raises(_write(tmp_path, lines), f"case.dat:{LINES_HDR}:", "no rows")


def test_no_points_section(tmp_path):
    lines = _lines_A()
    del lines[POINTS_HDR - 1 : LINES_HDR - 1]
    n = LINE_ROW - (LINES_HDR - POINTS_HDR)
    _raises(_write(tmp_path, lines), f"case.dat:{n}:", "AttachA = '1'", "no point with id 1")


@pytest.mark.parametrize("text", ["", "\n\n", "just some text\nand more\n1 2 3\n"])
def test_no_sections(tmp_path, text):
    p = tmp_path / "case.dat"
    p.write_text(text)
    _raises(p, "case.dat", "no sections")


# ----------------------------------------------------------------------------
# warnings
# ----------------------------------------------------------------------------


def test_unknown_option_warns_and_is_kept(tmp_path):
    deck_path = _mutate(tmp_path, {33: ["0 writeLog", "42.5  myOption  something", "fast  myMode"]})
    with pytest.warns(InputWarning, match="unknown option") as record:
        deck = read_deck(deck_path)
    assert deck.options["myOption"] == 42.5
    assert deck.options["myMode"] == "fast"
    assert any("case.dat:34:" in w for w in deck.warnings)
    assert any("myMode" in w for w in deck.warnings)
    assert len([r for r in record if "unknown option" in str(r.message)]) == 2


def test_ei_positive_is_read_without_warning(tmp_path):
    """Bending stiffness is modelled now (see tests/test_bending.py): read, no warning."""
    deck_path = _mutate(tmp_path, {T: GOOD_TYPE.replace("6236000.0  0.0", "6236000.0  1.5e4")})
    deck = read_deck(deck_path)
    assert deck.line_types["main"].ei == 1.5e4
    assert not any("bending" in w for w in deck.warnings)


def test_outputs_section_warns(tmp_path):
    deck_path = _mutate(tmp_path, {END_ROW: ["------ OUTPUTS ------", "FairTen1", "AnchTen1", "---- need this line ----"]})
    with pytest.warns(InputWarning, match="OUTPUTS"):
        deck = read_deck(deck_path)
    assert deck.lines == read_deck(CASE_A).lines


def test_text_after_need_this_line_is_ignored(tmp_path):
    lines = _lines_A() + ["garbage that would not parse", "---- LINES ----", "x"]
    deck = read_deck(_write(tmp_path, lines))
    assert deck.lines == read_deck(CASE_A).lines


def test_duplicate_option_warns_later_wins(tmp_path):
    deck_path = _mutate(tmp_path, {33: ["0 writeLog", "1e-4 dtM"]})  # dtM is given again on line 35
    with pytest.warns(InputWarning, match="dtM given again"):
        deck = read_deck(deck_path)
    assert deck.options["dtM"] == 3.3333333333333335e-05


def test_header_line_that_looks_like_data_warns(tmp_path):
    lines = _lines_A()
    del lines[POINTS_HDR + 1]  # drop the units line: row "1 Fixed ..." becomes the 2nd header line
    with pytest.warns(InputWarning, match="looks like a data row"):
        with pytest.raises(InputError, match="id 2 out of sequence"):
            read_deck(_write(tmp_path, lines))


def test_v1_point_forces_are_ignored_with_warning(tmp_path):
    deck_path = _mutate(tmp_path, {P2: "2  Coupled -5.2 0.0 -70.0  0 0  10 0 0  0.5 1.0"})
    with pytest.warns(InputWarning, match="external force"):
        deck = read_deck(deck_path)
    assert deck.points[2].cda == 0.5 and deck.points[2].ca == 1.0


def test_unattached_point_warns(tmp_path):
    deck_path = _mutate(tmp_path, {P2: ["2  Coupled -5.2 0.0 -70.0  0 0 0 0", "3  Fixed 0 0 -320  0 0 0 0"]})
    with pytest.warns(InputWarning, match="no line is attached"):
        deck = read_deck(deck_path)
    assert deck.points[3].attachment == "fixed"


def test_all_warnings_carry_file_and_line(tmp_path):
    deck_path = _mutate(tmp_path, {33: ["0 writeLog", "7 unknownThing", "8 otherThing"]})
    with pytest.warns(InputWarning):
        deck = read_deck(deck_path)
    assert len(deck.warnings) == 2
    for w in deck.warnings:
        assert re.search(r"case\.dat:\d+: ", w), w


def test_deck_without_lines_is_refused_naming_what_is_missing():
    # MoorDyn's tests/Mooring/rotations/nwu.txt: a coupled body with three points, no lines
    with pytest.raises(InputError, match=r"nwu.txt: the deck has no LINE TYPES and no LINES section "
                                         r"\(sections found: BODIES, OPTIONS, POINTS\).*add a LINES section"):
        read_deck(DATA / "public" / "nwu.txt")


def test_one_segment_line_is_built_with_two_segments_and_a_warning():
    """A deck's NumSegs = 1 (MoorDyn: a spring-damper between the ends) is built with
    2 segments and says so; an explicit ``--segments 1`` is refused with the reason."""
    from moorjax.io import build_scene
    from moorjax.io.errors import InputWarning

    text = CASE_A.read_text()
    assert "1  main  1  2  902.2  160  -" in text
    deck = parse_deck(text.replace("1  main  1  2  902.2  160  -", "1  main  1  2  902.2  1  -"), "one.dat")
    assert deck.lines[0].n_segments == 1
    with pytest.warns(InputWarning, match=r"one.dat:\d+: LINES id 1: NumSegs = 1 is built with 2 segments"):
        scene = build_scene(deck)
    assert scene.lines[0].n_segments == 2
    with pytest.raises(InputError, match=r"--segments 1: a line of one segment has no free node.*N >= 2"):
        build_scene(deck, segments=1)
