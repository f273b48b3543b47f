"""scene.checks: the validators at every boundary, each at its edges, with its one-line message."""

import re

import numpy as np
import pytest

from scene.checks import (
    check_array,
    check_between,
    check_choice,
    check_finite,
    check_int,
    check_mapping,
    check_positive,
    names,
    read_input_text,
    readonly,
    shown,
    used_or_refused,
)


def test_an_option_given_where_it_is_not_used_is_refused():
    assert used_or_refused("--m", 3, True, "unused", "why") is True
    assert used_or_refused("--m", None, False, "unused", "why") is False
    with pytest.raises(ValueError) as err:
        used_or_refused("--m", 3, False, "the swaps per update", "no greedy tasker runs")
    assert str(err.value) == "--m: the swaps per update; no greedy tasker runs"


def test_integers_of_more_than_16_digits_are_shown_in_six_significant_digits():
    assert shown(10**16 - 1) == "9999999999999999"                     # 16 digits: all of them
    assert shown(10**16) == "1e+16"
    assert shown(-(10**16)) == "-1e+16"
    assert shown(123456789012345678) == "1.23457e+17"
    assert shown(True) == "True" and shown(2.5e30) == "2.5e+30"


def test_names_lists_at_most_three_then_counts_the_rest():
    assert names(["a", "b", "c"]) == "a, b, c"
    assert names(["a", "b", "c", "d"]) == "a, b, c and 1 more"
    assert names(["a", "b"], most=1) == "a and 1 more"


def test_positive_numbers_and_zero_where_allowed():
    assert check_positive("r", 1e-300) == 1e-300
    assert check_positive("r", 0, allow_zero=True) == 0.0
    assert check_positive("r", 3, allow_zero=True) == 3.0
    for value in (0, -1, float("nan"), float("inf"), 10**400):
        with pytest.raises(ValueError, match=f"^r: expected a finite number > 0, got {re.escape(shown(value))}$"):
            check_positive("r", value)
    for value in (-1e-300, float("-inf")):
        with pytest.raises(ValueError, match=r"^r: expected a finite number >= 0, got -"):
            check_positive("r", value, allow_zero=True)


def test_a_range_open_at_its_low_end_refuses_that_end_and_infinity_is_never_in_range():
    assert check_between("speed", 1e-9, 0.0, 100.0, "m/s", low_open=True) == 1e-9
    assert check_between("speed", 100, 0.0, 100.0, "m/s", low_open=True) == 100.0
    assert check_between("noise", 0, 0.0, 255.0, "grey levels") == 0.0
    with pytest.raises(ValueError, match=r"^speed: expected a finite number > 0 and at most 100 m/s, got 0$"):
        check_between("speed", 0, 0.0, 100.0, "m/s", low_open=True)
    with pytest.raises(ValueError, match=r"^r: expected a finite number >= 0.001 m, got inf$"):
        check_between("r", float("inf"), 1e-3, np.inf, "m")
    with pytest.raises(ValueError, match=r"^r: expected a finite number >= 0.001 m, got -1e\+400$"):
        check_between("r", -(10**400), 1e-3, np.inf, "m")


def test_booleans_are_not_integers():
    assert check_int("n", np.int64(3), minimum=3) == 3
    with pytest.raises(ValueError, match=r"^people.count: expected an integer, got True$"):
        check_int("people.count", True)
    with pytest.raises(ValueError, match=r"^n: expected an integer >= 1, got 0$"):
        check_int("n", 0, minimum=1)


@pytest.mark.parametrize("value, shape, message", [
    ([10**400, 1], (2,), r"xy: expected finite numbers, got one beyond the float range"),
    ([[1, 2], [3]], (None, 2), r"xy: expected numbers of shape \(n, 2\)"),
    ([1.0, 2.0], (None, 2), r"xy: expected shape \(n, 2\), got \(2,\)"),
    ([[1.0, 2.0]], (2,), r"xy: expected shape \(2,\), got \(1, 2\)"),
    ([1.0, float("nan")], (2,), r"xy: expected finite numbers, got NaN or infinity"),
    ([[1.0, float("-inf")]], (None, 2), r"xy: expected finite numbers, got NaN or infinity"),
])
def test_arrays_of_the_wrong_shape_or_not_finite_are_one_line(value, shape, message):
    with pytest.raises(ValueError, match=f"^{message}$"):
        check_array("xy", value, shape)


def test_mappings_refuse_other_types_and_missing_keys():
    assert check_mapping("room", {"shape": "circle"}, ("shape", "radius"), ("shape",)) == {"shape": "circle"}
    with pytest.raises(ValueError, match=r"^room: expected a mapping, got list$"):
        check_mapping("room", [1, 2], ("shape",))
    with pytest.raises(ValueError, match=r"^room: missing key 'shape'$"):
        check_mapping("room", {"radius": 1.0}, ("shape", "radius"), ("shape",))


def test_readonly_copies_and_leaves_the_original_writable():
    a = np.zeros(3)
    r = readonly(a)
    a[0] = 5.0
    assert r[0] == 0.0 and a.flags.writeable and not r.flags.writeable


def test_an_empty_choice_is_not_one_of_the_valid_values():
    assert check_choice("backend", "osmesa", ("egl", "osmesa")) == "osmesa"
    with pytest.raises(ValueError, match=r"^backend: unknown value None; expected one of egl, osmesa$"):
        check_choice("backend", None, ("egl", "osmesa"))


def test_a_falsy_value_given_where_it_is_not_used_is_still_given():
    for value in (0, 0.0, ""):
        with pytest.raises(ValueError, match=r"^--m: unused; why$"):
            used_or_refused("--m", value, False, "unused", "why")


def test_a_file_that_is_not_utf8_names_its_first_bad_byte_and_where_it_is(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_bytes(b"name: caf\xc3\xa9 \xff\n")            # e-acute is UTF-8; 0xff at offset 12 is not
    with pytest.raises(ValueError) as err:
        read_input_text("scene file", path)
    assert str(err.value) == f"scene file: {str(path)!r} is not UTF-8 text (byte 0xff at offset 12)"
    path.write_bytes(b"name: caf\xc3\xa9\n")
    assert read_input_text("scene file", path) == "name: caf\u00e9\n"


def test_booleans_of_numpy_are_not_numbers_either():
    for value in (np.array([True, False]), [np.True_, 1.0], np.array([1.0, np.False_], dtype=object)):
        with pytest.raises(ValueError, match=r"^xy: expected numbers of shape \(2,\), got "):
            check_array("xy", value, (2,))
    assert check_array("xy", np.array([3, 4], dtype=np.uint8), (2,)).tolist() == [3.0, 4.0]


def test_the_first_unknown_or_missing_key_is_named():
    with pytest.raises(ValueError, match=r"^room: unknown key 'colour'; expected keys among shape, radius$"):
        check_mapping("room", {"colour": 1, "shape": "circle", "floor": 2}, ("shape", "radius"))
    with pytest.raises(ValueError, match=r"^room: missing key 'shape'$"):
        check_mapping("room", {}, ("shape", "radius", "height"), ("shape", "radius", "height"))


def test_finite_numbers_refuse_infinities_nan_and_what_is_not_a_number():
    assert check_finite("yaw", -45) == -45.0 and check_finite("yaw", np.float32(0.5)) == 0.5
    for value, shown_as in [(float("inf"), "inf"), (float("-inf"), "-inf"), (float("nan"), "nan"),
                            (-(10**400), "-1e+400")]:
        with pytest.raises(ValueError, match=f"^yaw: expected a finite number, got {re.escape(shown_as)}$"):
            check_finite("yaw", value)
    # None fails float() with a TypeError, a 0-d array of text with a ValueError; bytes would convert
    for value, shown_as in [(None, "None"), (np.array("abc"), "array('abc', dtype='<U3')"), (b"5", "b'5'"),
                            (True, "True"), ("5", "'5'")]:
        with pytest.raises(ValueError, match=f"^yaw: expected a number, got {re.escape(shown_as)}$"):
            check_finite("yaw", value)


def test_an_integer_is_returned_as_a_python_int_and_a_minimum_of_zero_is_still_a_minimum():
    n = check_int("n", np.int64(3))
    assert type(n) is int and n == 3
    assert check_int("n", 0, minimum=0) == 0
    with pytest.raises(ValueError, match=r"^n: expected an integer >= 0, got -1$"):
        check_int("n", -1, minimum=0)
    with pytest.raises(ValueError, match=r"^n: expected an integer, got 3.0$"):
        check_int("n", 3.0)


def test_bytes_in_an_array_are_not_numbers():
    # numpy would read b"5" as 5.0 without a word
    with pytest.raises(ValueError, match=r"^xy: expected numbers of shape \(2,\), got b'5'$"):
        check_array("xy", [b"5", 4.0], (2,))


def test_any_mapping_is_a_mapping_and_the_allowed_keys_may_come_from_a_generator():
    from types import MappingProxyType

    proxy = MappingProxyType({"shape": "circle"})
    assert check_mapping("room", proxy, ("shape", "radius")) is proxy
    with pytest.raises(ValueError, match=r"^room: unknown key 'colour'; expected keys among shape, radius$"):
        check_mapping("room", {"shape": "circle", "colour": 1}, (k for k in ("shape", "radius")))


def test_a_range_refuses_what_lies_above_its_high_end():
    assert check_between("noise", 255, 0.0, 255.0, "grey levels") == 255.0
    with pytest.raises(ValueError, match=r"^noise: expected a finite number >= 0 and at most 255 grey levels, got 255.5$"):
        check_between("noise", 255.5, 0.0, 255.0, "grey levels")
