"""The rotating drum's bed geometry (`tidem.heat.drum_heat`): a bed filling a drum's cross-section below a
tilted line gives back the line's slope (dynamic angle of repose) and the central angle under it."""

import math

import numpy as np
import pytest

from tidem.heat.drum_heat import free_surface


@pytest.mark.parametrize("angle", [20.0, 35.0])
def test_free_surface_of_a_segment_below_a_tilted_chord(angle):
    R, d, depth = 0.1, 0.002, 0.04  # chord 0.04 m below the axis
    g = np.arange(-R, R, d) + 0.5 * d
    x, z = (a.ravel() for a in np.meshgrid(g, g))
    slope = math.tan(math.radians(angle))
    line = -depth / math.cos(math.radians(angle)) + slope * x  # distance `depth` from the axis
    keep = (np.hypot(x, z) < R - 0.5 * d) & (z + 0.5 * d <= line)
    pts = np.stack([x[keep], np.zeros(keep.sum()), z[keep]], axis=1)
    got_angle, p = free_surface(pts, np.full(len(pts), 0.5 * d), (0, 0, 0), (0, 1, 0), (0, 0, -9.81))
    assert got_angle == pytest.approx(angle, abs=1.5)
    assert p == pytest.approx(depth, abs=d)
    assert math.degrees(2 * math.acos(p / R)) == pytest.approx(math.degrees(2 * math.acos(depth / R)), abs=3.0)
