"""The shared time-table CSV reader (moorjax.io.table): measured tensions, results."""

import numpy as np
import pytest

from moorjax.identify import read_target
from moorjax.io.errors import InputError
from moorjax.io.table import read_table


def test_simulate_csv_reads_back_by_column(tmp_path):
    p = tmp_path / "run.csv"
    p.write_text("t,L1_tension_a,L1_tension_b\n# units: s,N,N\n0.05,1.5,2.5\n0.1,1.25,2.75\n")
    cols = read_target(p)
    assert list(cols) == ["t", "L1_tension_a", "L1_tension_b"]
    np.testing.assert_array_equal(cols["t"], [0.05, 0.1])
    np.testing.assert_array_equal(cols["L1_tension_b"], [2.5, 2.75])
    table = read_table(p)
    assert table.header_line == 1 and [r[0] for r in table.rows] == [3, 4]


@pytest.mark.parametrize("text, fragments", [
    ("", ["empty", "t,L<id>_tension_b"]),
    ("T,L1_tension_b,l1_TENSION_B\n0,1,1\n1,1,1\n", [":1:", "appears twice"]),
    ("t,L1_tension_b\n0,1\n", ["1 data row(s)", "at least 2"]),
    ("t,L1_tension_b\n0,1\n1,abc\n", [":3:", "'L1_tension_b'", "'abc'", "not a number"]),
    ("t,L1_tension_b\n0,1\n1,inf\n", [":3:", "finite"]),
    ("t,L1_tension_b\n0,1\n1\n", [":3:", "1 cells, expected 2"]),
    ("t,L1_tension_b\n0,1\n0,2\n", [":3:", "'t' = 0 s", "previous time 0 s", "strictly increasing"]),
])
def test_target_errors_are_input_errors_naming_file_and_line(tmp_path, text, fragments):
    p = tmp_path / "target.csv"
    p.write_text(text)
    with pytest.raises(InputError) as info:
        read_target(p)
    msg = str(info.value)
    assert msg.startswith(str(p))
    for f in fragments:
        assert f in msg, f"{f!r} not in {msg!r}"
