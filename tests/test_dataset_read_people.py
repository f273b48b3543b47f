"""testbed.dataset.read_people: one row per person and frame, with the documented columns, or one line naming the file."""

import numpy as np
import pytest

from testbed.dataset import read_people

HEADER = "frame,person_id,x,y,radius,height\n"


def test_one_row_is_a_table_of_one_row(tmp_path):
    """One person in one frame came back as a 0-d array: len() raised TypeError."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER + "0,0,1.5,2.25,0.25,1.75\n")
    table = read_people(path)
    assert table.shape == (1,) and len(table) == 1
    assert table["x"].tolist() == [1.5] and table["height"].tolist() == [1.75]


def test_no_one_gives_the_documented_columns_and_types(tmp_path):
    """A scene of no people (header only) came back with every column bool."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER)
    table = read_people(path)
    assert table.shape == (0,)
    assert table.dtype.names == ("frame", "person_id", "x", "y", "radius", "height")
    assert [table.dtype[n].kind for n in table.dtype.names] == ["i", "i", "f", "f", "f", "f"]


def test_many_rows_keep_integers_and_floats(tmp_path):
    path = tmp_path / "people.csv"
    path.write_text(HEADER + "0,0,1,2,0.25,1.75\n0,1,3,4.5,0.25,1.75\n")
    table = read_people(path)
    assert table["person_id"].tolist() == [0, 1] and table["person_id"].dtype.kind == "i"
    np.testing.assert_array_equal(table["x"], [1.0, 3.0])
    assert table["x"].dtype.kind == "f"


def test_a_file_without_the_columns_is_one_line_naming_it(tmp_path):
    """Any CSV came back as a table of its own columns; the error came at the first use of x."""
    path = tmp_path / "people.csv"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match=r"people\.csv: no column 'frame'") as exc:
        read_people(path)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize(("row", "says"), [
    ("0,,1,2,0.25,1.75", "column 'person_id', row 1: expected a whole number, got an empty field"),
    ("1.5,0,1,2,0.25,1.75", "column 'frame', row 1: expected a whole number, got 1.5"),
    ("0,0,nan,2,0.25,1.75", "column 'x', row 1: expected a finite number, got nan"),
    ("0,0,1,2,0.25,1.75\n0,1,1,2,0.25,1.75\n0,2,inf,2,0.25,1.75", "column 'x', row 3: expected a finite number, got inf"),
])
def test_a_value_that_is_not_a_position_is_one_line_naming_it(tmp_path, row, says):
    """An empty field came back as person -1, a frame 1.5 as frame 1, nan as a position."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER + row + "\n")
    with pytest.raises(ValueError) as err:
        read_people(path)
    assert str(err.value) == f"{path}: {says}"


@pytest.mark.parametrize("text", ["", "\n\n"])
def test_an_empty_file_is_one_line_naming_it(tmp_path, text, recwarn):
    """An empty file raised IndexError from numpy (a traceback out of `camtask export`) after a
    UserWarning "Empty input file"."""
    path = tmp_path / "people.csv"
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        read_people(path)
    assert str(err.value) == f"{path}: no header line (expected frame,person_id,x,y,radius,height)"
    assert not recwarn.list
