"""Shared fixtures: the lab scene and one renderer per test session (one GL context per process)."""

import os

import numpy as np
import pytest
from hypothesis import settings

from scene import load_scene

# Property tests draw new examples on every local run (that is how they find bugs); under
# CI they draw the same ones each time, so a red CI means the change, not the draw.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture(scope="session")
def lab():
    """The built-in lab scene (16 calibrated cameras, 3 people)."""
    return load_scene("lab")


@pytest.fixture(scope="session")
def lab_renderer(lab):
    """A :class:`render.Renderer` of the lab, all cameras, reused by every rendering test."""
    from render import Renderer

    with Renderer(lab) as r:
        yield r


@pytest.fixture
def three_people():
    """Three people standing apart in the lab, (3, 2) metres, world frame."""
    return np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
