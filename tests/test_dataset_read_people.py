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
    path.write_text("frame,person_id,x,y,radius\n0,0,1,2,0.25\n")      # only the last one missing
    with pytest.raises(ValueError) as exc:
        read_people(path)
    assert str(exc.value) == f"{path}: no column 'height' (expected the header frame,person_id,x,y,radius,height)"


def test_values_come_back_as_written(tmp_path):
    """Decimals that no binary fraction holds read back as the same float64, not a coarser float."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER + "0,0,0.1,2.7,0.23,1.83\n")
    assert read_people(path).tolist() == [(0, 0, 0.1, 2.7, 0.23, 1.83)]


@pytest.mark.parametrize(("rows", "says"), [
    ("0,0,abc,2,0.25,1.75\n", "column 'x': expected numbers, got text"),
    ("0,0,nan,2,0.25,1.75\n0,1,,2,0.25,1.75\n", "column 'x', row 1: expected a finite number, got nan"),
])
def test_a_file_that_is_not_a_table_of_numbers_is_one_line_naming_it(tmp_path, rows, says):
    """A word makes a column of text; the first bad row is named with its own value."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER + rows)
    with pytest.raises(ValueError) as err:
        read_people(path)
    assert str(err.value) == f"{path}: {says}"


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


def test_a_short_row_is_one_line_naming_the_file_and_the_line(tmp_path):
    """numpy's message spans two lines: "Some errors were detected !\\n    Line #3 (got 3 columns ...)"."""
    path = tmp_path / "people.csv"
    path.write_text(HEADER + "0,0,1,2,0.25,1.75\n0,1,1\n")
    with pytest.raises(ValueError) as err:
        read_people(path)
    assert str(err.value).startswith(f"{path}: cannot read (") and "Line #3 (got 3 columns" in str(err.value)
    assert "\n" not in str(err.value)
