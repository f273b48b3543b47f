"""Tests of the tasking core's input checks: each helper's exact message and what it accepts."""

import re

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from tasking.checks import (
    check_angles,
    check_camera_radii,
    check_cameras_outside_discs,
    check_discs_disjoint,
    check_discs_in_room,
    check_fov,
    check_indices,
    check_int,
    check_points,
    check_radii,
    check_room,
)

SQUARE = box(-1.0, -1.0, 1.0, 1.0)


def raises(message):
    """``pytest.raises`` for a ValueError whose whole message is ``message``."""
    return pytest.raises(ValueError, match="^" + re.escape(message) + "$")


# --- check_points ---------------------------------------------------------------------


def test_points_are_converted_to_floats():
    arr = check_points("centers", [[0, 1], [2, 3]])
    assert arr.dtype == float
    np.testing.assert_array_equal(arr, [[0.0, 1.0], [2.0, 3.0]])


@pytest.mark.parametrize("empty", [[], np.empty(0), np.empty((0, 2))])
def test_empty_points_are_a_0_by_2_array_when_allowed(empty):
    arr = check_points("centers", empty, allow_empty=True)
    assert arr.shape == (0, 2) and arr.dtype == float


def test_empty_points_are_refused_unless_allowed():
    with raises("camera_xy must not be empty"):
        check_points("camera_xy", np.empty((0, 2)))
    with raises("camera_xy must have shape (n, 2); got shape (0,)"):
        check_points("camera_xy", [])


@pytest.mark.parametrize(
    "points, shape",
    [([1.0, 2.0], (2,)), ([[1.0, 2.0, 3.0]], (1, 3)), ([[[1.0, 2.0]]], (1, 1, 2)),
     (np.empty((2, 0)), (2, 0))],
)
@pytest.mark.parametrize("allow_empty", [False, True])
def test_points_of_another_shape_are_refused(points, shape, allow_empty):
    with raises(f"centers must have shape (n, 2); got shape {shape}"):
        check_points("centers", points, allow_empty=allow_empty)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_points_must_be_finite(bad):
    with raises("centers must be finite (no NaN or inf coordinates)"):
        check_points("centers", [[0.0, 0.0], [1.0, bad]], allow_empty=True)


# --- check_angles, check_fov ----------------------------------------------------------


def test_angles_are_an_n_vector_of_finite_floats():
    np.testing.assert_array_equal(check_angles("camera_yaw", [0, 1], 2), [0.0, 1.0])
    with raises("camera_yaw must have shape (2,); got shape ()"):
        check_angles("camera_yaw", 1.0, 2)
    with raises("camera_yaw must have shape (2,); got shape (3,)"):
        check_angles("camera_yaw", [0.0, 1.0, 2.0], 2)
    with raises("camera_yaw must be finite (no NaN or inf)"):
        check_angles("camera_yaw", [0.0, np.inf], 2)
    with raises("camera_yaw must have shape (2,); got shape (1, 2)"):     # the right size is not enough
        check_angles("camera_yaw", [[0.0, 1.0]], 2)


def test_fov_scalar_is_broadcast_and_may_exceed_pi():
    np.testing.assert_array_equal(check_fov(4.0, 3), [4.0, 4.0, 4.0])
    np.testing.assert_array_equal(check_fov([1.0, 6.0], 2), [1.0, 6.0])


@pytest.mark.parametrize(
    "fov, message",
    [
        ([1.0, 1.0, 1.0], "fov must be a scalar or have shape (2,); got shape (3,)"),
        ([1.0], "fov must be a scalar or have shape (2,); got shape (1,)"),     # not broadcast like a scalar
        ([1.0, np.nan], "fov must be finite (no NaN or inf)"),
        ([1.0, 0.0], "fov must be in (0, 2*pi) radians; got 0..1"),
        ([-0.5, 2.0], "fov must be in (0, 2*pi) radians; got -0.5..2"),
        ([1.5, 2 * np.pi], "fov must be in (0, 2*pi) radians; got 1.5..6.28319"),
        ([7.0, 3.0], "fov must be in (0, 2*pi) radians; got 3..7"),
        ([[1.0, 1.0]], "fov must be a scalar or have shape (2,); got shape (1, 2)"),   # two values, not a row
    ],
)
def test_fov_errors(fov, message):
    with raises(message):
        check_fov(fov, 2)


# --- check_radii, check_camera_radii --------------------------------------------------


def test_radii_scalar_is_broadcast():
    np.testing.assert_array_equal(check_radii("radii", 0.2, 3), [0.2, 0.2, 0.2])
    np.testing.assert_array_equal(check_radii("radii", [1, 2], 2), [1.0, 2.0])
    assert check_radii("radii", 0.2, 0).shape == (0,)


@pytest.mark.parametrize("bad", [0.0, -0.1, np.nan, np.inf])
def test_radii_must_be_finite_and_positive(bad):
    with raises("radius must be finite and > 0"):
        check_radii("radius", [0.1, bad], 2)


def test_radii_of_another_shape_are_refused():
    with raises("radii must be a scalar or have shape (2,); got shape (3,)"):
        check_radii("radii", [0.1, 0.1, 0.1], 2)
    with raises("radii must be a scalar or have shape (2,); got shape (2, 1)"):
        check_radii("radii", [[0.1], [0.1]], 2)


def test_camera_radii_may_be_zero_or_infinite():
    np.testing.assert_array_equal(check_camera_radii("near", 0.0, 2), [0.0, 0.0])
    np.testing.assert_array_equal(check_camera_radii("far", [np.inf, 3], 2), [np.inf, 3.0])


@pytest.mark.parametrize("bad", [-0.1, -np.inf, np.nan])
def test_camera_radii_must_be_non_negative_numbers(bad):
    with raises("far must be >= 0 metres (inf allowed), not NaN"):
        check_camera_radii("far", [1.0, bad], 2)


def test_camera_radii_of_another_shape_are_refused():
    with raises("near must be a scalar or have shape (2,); got shape (1,)"):
        check_camera_radii("near", [0.1], 2)
    with raises("near must be a scalar or have shape (2,); got shape (1, 2)"):
        check_camera_radii("near", [[0.1, 0.2]], 2)


# --- check_room -----------------------------------------------------------------------


def test_room_is_returned_as_given():
    assert check_room(SQUARE) is SQUARE


@pytest.mark.parametrize(
    "room",
    [
        Polygon(),
        Polygon([(0, 0), (1, 0), (2, 0)]),                  # collapsed to a line
        Polygon([(0, 0), (2, 2), (2, 0), (0, 1)]),          # a bow tie, of positive area
    ],
)
def test_room_must_be_a_valid_polygon_of_positive_area(room):
    with raises("room must be a valid Polygon with positive area"):
        check_room(room)


def test_room_of_a_valid_ring_whose_area_underflows_to_0_is_refused():
    """Legs of 2e-162 m: GEOS finds the ring valid, but its area e**2 / 2 is below the smallest
    float, so the room's area is 0."""
    tiny = Polygon([(0, 0), (2e-162, 0), (0, 2e-162)])
    assert tiny.is_valid and not tiny.is_empty and tiny.area == 0.0
    with raises("room must be a valid Polygon with positive area"):
        check_room(tiny)


def test_room_must_be_a_polygon():
    with raises("room must be a shapely Polygon; got MultiPolygon"):
        check_room(SQUARE.union(box(3, 3, 4, 4)))


# --- check_int ------------------------------------------------------------------------


def test_int_accepts_its_bounds_and_numpy_integers():
    assert check_int("k", 1, 1, 5) == 1
    assert check_int("k", 5, 1, 5) == 5
    value = check_int("max_subsets", np.int64(10**9), 1)
    assert value == 10**9 and type(value) is int


@pytest.mark.parametrize(
    "value, hi, message",
    [
        (0, 5, "k must be >= 1 and <= 5; got 0"),
        (6, 5, "k must be >= 1 and <= 5; got 6"),
        (0, None, "k must be >= 1; got 0"),
        (True, 5, "k must be an integer; got True"),
        (2.0, 5, "k must be an integer; got 2.0"),
        ("2", None, "k must be an integer; got '2'"),
    ],
)
def test_int_errors(value, hi, message):
    with raises(message):
        check_int("k", value, 1, hi)


# --- check_indices --------------------------------------------------------------------


def test_indices_are_sorted_intp():
    arr = check_indices("current", [2, 0], 3, size=2)
    assert arr.dtype == np.intp
    np.testing.assert_array_equal(arr, [0, 2])


def test_no_indices_are_an_empty_intp_array():
    arr = check_indices("current", [], 3)
    assert arr.shape == (0,) and arr.dtype == np.intp


@pytest.mark.parametrize(
    "indices, size, message",
    [
        ([[0, 1]], None, "current must be a 1-D sequence of integer indices"),
        ([0.0, 1.0], None, "current must be a 1-D sequence of integer indices"),
        ([0, 1, 2], 2, "current must hold 2 indices; got 3"),
        ([], 1, "current must hold 1 indices; got 0"),
        ([-1, 0], None, "current must be 0-based indices in [0, 2]"),
        ([0, 3], None, "current must be 0-based indices in [0, 2]"),
        ([1, 1], 2, "current must not repeat an index"),
    ],
)
def test_indices_errors(indices, size, message):
    with raises(message):
        check_indices("current", indices, 3, size=size)


# --- discs ----------------------------------------------------------------------------


def test_disjoint_discs_may_touch_up_to_rounding():
    # 0.3 - 0.1 is 0.19999999999999998 in floats: short of the radii's sum by 3e-17 m
    check_discs_disjoint(np.array([[0.1, 0.0], [0.3, 0.0]]), np.array([0.1, 0.1]))
    check_discs_disjoint(np.array([[0.0, 0.1], [0.0, 0.3]]), np.array([0.1, 0.1]))
    check_discs_disjoint(np.array([[0.0, 0.0]]), np.array([5.0]))


@pytest.mark.parametrize(
    "centres, message",
    [
        ([[0.0, 0.0], [0.19, 0.0]], "centers: objects 0 and 1 overlap (distance 0.19 m)"),
        ([[0.0, 0.0], [0.0, 0.19]], "centers: objects 0 and 1 overlap (distance 0.19 m)"),
        ([[0.0, 0.0], [5.0, 5.0], [5.09, 5.12]],
         "centers: objects 1 and 2 overlap (distance 0.15 m)"),
    ],
)
def test_overlapping_discs_are_named(centres, message):
    with raises(message):
        check_discs_disjoint(np.array(centres), np.full(len(centres), 0.1))


def test_discs_of_different_radii_overlap_by_the_sum_of_their_own_radii():
    """Radii 0.1 and 0.3: centres 0.5 m apart are clear (0.5 > 0.4), 0.35 m apart overlap."""
    check_discs_disjoint(np.array([[0.0, 0.0], [0.5, 0.0]]), np.array([0.1, 0.3]))
    check_discs_disjoint(np.array([[0.5, 0.0], [0.0, 0.0]]), np.array([0.3, 0.1]))
    with raises("centers: objects 0 and 1 overlap (distance 0.35 m)"):
        check_discs_disjoint(np.array([[0.0, 0.0], [0.35, 0.0]]), np.array([0.1, 0.3]))


def test_discs_overlapping_by_a_nanometre_are_refused():
    """Only rounding (1e-12 m) is forgiven: discs of 0.25 m whose centres are 0.5 m - 1e-9 m
    apart overlap."""
    with raises("centers: objects 0 and 1 overlap (distance 0.5 m)"):
        check_discs_disjoint(np.array([[0.0, 0.0], [0.5 - 1e-9, 0.0]]), np.array([0.25, 0.25]))


def test_overlapping_discs_message_carries_the_name():
    with raises("estimates: objects 0 and 1 overlap (distance 0 m)"):
        check_discs_disjoint(np.zeros((2, 2)), np.array([0.1, 0.1]), name="estimates")


def test_discs_in_room_count_its_boundary_as_inside():
    check_discs_in_room(np.array([[1.0, 0.0], [0.0, -1.0], [0.5, 0.5]]), SQUARE)


def test_first_disc_outside_the_room_is_named():
    centres = np.array([[0.0, 0.0], [1.5, 0.0], [0.0, 2.0]])
    with raises("centers: object 1 at [1.5, 0.0] is outside the room"):
        check_discs_in_room(centres, SQUARE)
    with raises("estimates: object 0 at [0.0, 2.0] is outside the room"):
        check_discs_in_room(centres[2:], SQUARE, name="estimates")


def test_cameras_may_stand_on_a_disc_up_to_rounding():
    # 0.3 - 0.1 is 0.19999999999999998: short of the radius by 3e-17 m
    check_cameras_outside_discs(np.array([[0.3, 0.0], [0.1, 0.2]]), np.array([[0.1, 0.0]]),
                                np.array([0.2]))
    check_cameras_outside_discs(np.array([[0.0, 0.0]]), np.empty((0, 2)), np.empty(0))


@pytest.mark.parametrize(
    "cameras, message",
    [
        ([[1.0, 1.0], [0.15, 0.0]], "camera_xy: camera 1 is inside object 0"),
        ([[0.0, 0.15], [1.0, 1.0]], "camera_xy: camera 0 is inside object 0"),
        ([[1.0, 1.0], [2.0, 2.05]], "camera_xy: camera 1 is inside object 1"),
        ([[0.15, 0.0], [2.0, 2.05]], "camera_xy: camera 0 is inside object 0"),
    ],
)
def test_first_camera_inside_a_disc_is_named(cameras, message):
    centres, radii = np.array([[0.0, 0.0], [2.0, 2.0]]), np.array([0.2, 0.1])
    with raises(message):
        check_cameras_outside_discs(np.array(cameras), centres, radii)


def test_a_camera_a_nanometre_inside_a_disc_is_refused():
    with raises("camera_xy: camera 0 is inside object 0"):
        check_cameras_outside_discs(np.array([[0.25 - 1e-9, 0.0]]), np.zeros((1, 2)), np.array([0.25]))


def test_camera_inside_the_only_disc_is_found():
    with raises("camera_xy: camera 0 is inside object 0"):
        check_cameras_outside_discs(np.array([[0.05, 0.0]]), np.zeros((1, 2)), np.array([0.1]))


def test_empty_points_of_another_width_are_refused_even_when_allowed():
    with raises("centers must have shape (n, 2); got shape (0, 3)"):
        check_points("centers", np.empty((0, 3)), allow_empty=True)
