"""Viscoelastic and Syrope line types are refused, naming what moorjax lacks.

MoorDyn v2 (docs/inputs.rst, "Line Types" note and "Syrope Model for
Polyester Lines") reads ``EA_s|EA_d`` (constant dynamic stiffness),
``EA_s|EA_Dc|EA_D_Lm`` (load-dependent dynamic stiffness),
``SYROPE:file|EA_Dc|EA_D_Lm`` and ``BA_s|BA_d``. moorjax has no dynamic
branch per segment yet, so each form is refused with the deck line, the value
and the missing pieces; the type rows are those of MoorDyn's
``tests/Mooring/polyester/visco.txt`` and ``tests/Mooring/syrope/*/line.txt``.
"""

from __future__ import annotations

import pytest

from moorjax.io import parse_deck
from moorjax.io.errors import InputError

DECK = """t
---------------------- LINE TYPES -----------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI   Cd   Ca   CdAx  CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (-)  (-)  (-)  (-)   (-)
rope  0.1438  22.42  {ea}  {ba}  0.0  0  0  0.0  0.0
---------------------- POINTS ---------------------------------------
ID  Attachment  X     Y    Z      Mass  Volume  CdA  Ca
(#) (-)         (m)   (m)  (m)    (kg)  (m^3)   (m2) (-)
1   Fixed       0     0    -50    0     0       0    0
2   Fixed       60    0    -5     0     0       0    0
---------------------- LINES ----------------------------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#) (name)    (#)      (#)      (m)       (-)      (-)
1   rope      1        2        80        4        -
---------------------- OPTIONS --------------------------------------
50        WtrDpth
----------------------- need this line ------------------------------
"""


@pytest.mark.parametrize("ea, ba, words", [
    ("1.424e+08|1.586e+08|0.4", "4E9|11E6",
     ["deck.dat:5:", "EA_s|EA_Dc|EA_D_Lm: load-dependent", "dynamic) spring-dashpot branch",
      "internal strain per segment", "EA_d = EA_Dc + EA_D_Lm*mean_load", "BA_d"]),
    ("1.424e+08|1.586e+08", "-0.8",
     ["EA_s|EA_d: constant dynamic stiffness", "internal strain per segment"]),
    ("SYROPE:syrope.dat|1.53e8|23.12", "5.0e10|1.0e5",
     ["Syrope polyester model", "working curves", "OWC", "k1, k2", "SYROPE IC", "Tmax0, Tmean0",
      "EA_d = EA_Dc"]),
    ("1.424e+08", "4E9|11E6", ["BA_s|BA_d", "viscoelastic line model", "dynamic spring-dashpot branch"]),
])
def test_viscoelastic_forms_are_refused_naming_what_is_missing(ea, ba, words):
    with pytest.raises(InputError) as err:
        parse_deck(DECK.format(ea=ea, ba=ba), "deck.dat")
    msg = str(err.value)
    assert f"LINE TYPES 'rope'" in msg
    for w in words:
        assert w in msg, (w, msg)
