"""What happens in an episode: who is in the scene and where they walk.

Both ``camtask render`` and ``camtask run`` draw the walk with :func:`walk`, from the
first of two generators spawned from a seed (the second draws the sensor noise), so
the same generator gives the same people on the same paths. ``run`` spawns them from
``SeedSequence(seed)``, a dataset's episode i from ``SeedSequence(seed, spawn_key=(i,))``
(:func:`testbed.episodes.episode_seed`): ``run --seed S`` does not walk the paths of
episode 0 of ``render --seed S``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from scene import Scene
from scene.config import check_people_capacity, default_colours
from scene.motion import random_drop, random_waypoint


def with_people(scene: Scene, count: int | None, *, option: str = "--people") -> Scene:
    """``scene`` with ``count`` people (its own number when None); default colours as needed."""
    if count is None or count == scene.people.count:
        return scene
    if count < 0:
        raise ValueError(f"{option}: expected a number >= 0, got {count}")
    check_people_capacity(option, count, scene.people.radius, scene.room)
    colours = default_colours(count).astype(np.uint8)
    colours[: min(count, scene.people.count)] = scene.people.colours[:count]
    people = dataclasses.replace(scene.people, count=count, colours=colours, positions=None)
    return dataclasses.replace(scene, people=people)


def check_renderable(scene: Scene, option: str) -> None:
    """Raise a one-line ValueError naming ``option`` unless every camera of ``scene`` is
    calibrated and can be rectified to a level camera (checked before any rendering)."""
    from pipeline.rectify import check_rectifiable

    if not scene.is_calibrated:
        raise ValueError(f"{option}: {scene.name!r} has floor-plane cameras only; rendering needs calibrated "
                         "cameras (the circular simulation is `camtask study cameras`, `static`, `moving`, `tracking`)")
    check_rectifiable(scene.cameras)


def check_people_renderable(scene: Scene, option: str) -> None:
    """Raise a one-line ValueError naming ``option`` when the scene has more people than a
    frame's uint8 labels hold (before the walk: 10**5 small people took minutes to drop)."""
    from render.raster import MAX_PEOPLE

    if scene.people.count > MAX_PEOPLE:
        raise ValueError(f"{option}: expected at most {MAX_PEOPLE} people (uint8 labels), got {scene.people.count}")


def walk(scene: Scene, frames: int, rng: np.random.Generator, progress=None) -> np.ndarray:
    """Random-waypoint positions of the scene's people, (frames, people, 2) float, metres.

    progress : optional callable, called with 1 after each frame's step but the first
    """
    people = scene.people
    if people.count == 0:
        return np.zeros((frames, 0, 2))
    radii = np.full(people.count, people.radius)
    initial = people.positions if people.positions is not None else \
        random_drop(scene.room.polygon, radii, rng)
    return random_waypoint(scene.room.polygon, radii, frames, scene.dt, people.speed, rng,
                           initial=initial, progress=progress)
