"""Reader for MoorDyn v2 input files ("decks") into plain, validated data.

The deck format (MoorDyn v2, also the v1 section names) is a plain-text file:

* free-text lines before the first section (kept as :attr:`Deck.title`);
* sections, each opened by a line containing ``---`` and a keyword
  (``LINE TYPES``/``LINE DICTIONARY``, ``POINTS``/``POINT PROPERTIES``/
  ``CONNECTION PROPERTIES``/``NODE PROPERTIES``, ``LINES``/``LINE PROPERTIES``,
  ``OPTIONS``, ``BODIES``, ``RODS``, ``ROD TYPES``, ``FAILURE``, ``OUTPUTS``,
  ``CONTROL``, ``EXTERNAL LOADS``);
* table sections have two header lines (column names, units) then one row per
  object; ``OPTIONS`` rows are ``value  name  [description]``;
* the file ends at a ``---`` line containing ``need this line`` or at EOF.

Values are whitespace-separated; ``!``, ``#`` and ``%`` start a comment.
Blank lines inside sections are skipped.

Only what moorjax can simulate is accepted: lines between ``Fixed``/``Anchor``,
``Coupled``/``Vessel`` and ``Free``/``Connect`` points and points fixed in
bodies (``Body1``, ...).
``BODIES`` rows of every kind (``fixed``, ``coupled``, ``free``,
``coupledpinned``) are read into :class:`DeckBody` records;
:func:`moorjax.io.build_scene` builds fixed and coupled ones and refuses the
others with the reason.  Currents (``Currents`` 1, 2 and 5) and waves
(``WaveKin`` 2, 3 and 7) are read from MoorDyn's side files
(:mod:`moorjax.io.currents`, :mod:`moorjax.io.waves`). Rods,
failures, external loads and other wave modes raise
:class:`InputError` ("not supported yet"). ``SeafloorFile`` bathymetry
grids are read (:mod:`moorjax.io.seafloor`).
Everything is validated on reading; every error names ``file:line``, the
field, the value as written, its unit and what is expected.

Units are SI throughout (m, kg, N, s).  Axes follow MoorDyn: z up, z = 0 at the
free surface, seabed at z = -WtrDpth.

Pure Python + numpy; no JAX.

The package: :mod:`._lexer` (sections, rows, field parsers), :mod:`._options`
(``OPTIONS`` and MoorDyn's defaults), one module per object section
(:mod:`._line_types`, :mod:`._bodies`, :mod:`._points`, :mod:`._lines`), the
records they produce (:mod:`._records`) and :mod:`._reader`, which reads the
sections in order and cross-checks them into a :class:`Deck`.
"""

from ._options import MOORDYN_DEFAULTS as MOORDYN_DEFAULTS
from ._options import options_with_defaults as options_with_defaults
from ._reader import parse_deck as parse_deck
from ._reader import read_deck as read_deck
from ._records import Deck as Deck
from ._records import DeckBody as DeckBody
from ._records import DeckLine as DeckLine
from ._records import DeckLineType as DeckLineType
from ._records import DeckPoint as DeckPoint

__all__ = [
    "DeckLineType",
    "DeckPoint",
    "DeckBody",
    "DeckLine",
    "Deck",
    "read_deck",
    "parse_deck",
    "options_with_defaults",
    "MOORDYN_DEFAULTS",
]
