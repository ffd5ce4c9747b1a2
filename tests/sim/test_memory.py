"""The memory estimate (`tidem.sim.memory`): readable sizes, the scene-only estimate before any
allocation, and the same field bytes as the built model."""

import math

import pytest
import taichi as ti

from tests.conftest import make_scene
from tests.kernels.test_gas_averaging import fixed_grains, lattice_bed
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.sim import memory
from tidem.sim.model import build_model


@pytest.mark.parametrize("n, text", [(0, "0 B"), (512, "512 B"), (1536, "1.5 KiB"), (3.2 * 2**40, "3.2 TiB"),
                                     (1000 * 2**50, "1000 PiB"), (234.4 * 2**30, "234 GiB"), (1.2e33, "1.2e+33 B")])
def test_sizes_are_readable(n, text):
    assert memory.format_bytes(n) == text


def test_counts_switch_to_scientific_notation():
    assert memory.format_count(123456) == "123456"
    assert memory.format_count(7.9e9) == "7.9e+09"


def fill(diameter):
    return make_scene(particles=[{"name": "bed", "material": "steel", "diameter": {"value": diameter},
                                  "region": {"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1]}}])


def test_a_fill_too_large_is_refused_before_its_lattice_is_made(monkeypatch):
    import tidem.particles.placement

    def never(*args, **kwargs):
        raise AssertionError("the lattice was made")
    monkeypatch.setattr(tidem.particles.placement, "lattice_sites", never)
    with pytest.raises(SceneError) as err:
        build_model(validate(fill(1e-5)))
    msg = str(err.value)
    assert "particles[0].region: the fields of 7.5e+12 particles" in msg and "larger particles" in msg
    assert "numerics.max_neighbors" in msg and " PiB" in msg


def test_the_scene_estimate_matches_the_built_model():
    scene = validate(fill(0.01))
    model = build_model(scene)
    items = {it.key: it.bytes for it in memory.scene_items(scene.scene)}
    fields = items["particles[0].region"] - model.capacity * memory.HOST_BYTES_PER_PARTICLE
    sort_copy = items["numerics.sort_interval"]  # 6859 particles re-sort their storage through a scratch copy
    assert sort_copy == fields + items["numerics.max_neighbors"]
    assert fields + items["numerics.max_neighbors"] + sort_copy == \
        model.memory_bytes() - model.grid.n_cells * memory.CELL_BYTES
    assert memory.lattice_site_count(scene.scene.particles[0].region, 0.0102, "cubic") == model.capacity


@pytest.mark.parametrize("drag_averaging, tube_shape", [("cells", "cut"), ("length", "cells")])
def test_the_gas_estimate_counts_every_field_a_cell_has(solver_for, drag_averaging, tube_shape):
    """The gas grid's allocated fields, each counted as cells, faces or layers, against `gas_cell_bytes` (the
    averaging-length filters' scratch fields and the cut tube's gas parts and apertures included) plus
    `gas_band_bytes`, the direct solve's band of this thin grid."""
    raw = fixed_grains(lattice_bed(hole=(0.015, 0.03, 0.0046)), 0.003, length=0.012, tube=True)
    raw["gas"].update(drag_averaging=drag_averaging, tube_shape=tube_shape)
    s = solver_for(raw)
    gas = s.gas
    cells = math.prod(gas.gg.cells)
    per_cell = 0
    for name, value in vars(gas.G).items():
        for field in value if isinstance(value, list) else [value]:
            size = math.prod(field.shape)
            if 2 * size >= cells:
                per_cell += round(size / cells) * (4 if field.dtype in (ti.f32, ti.i32) else 8)
    filters = memory.gas_filters(s.model.scene, gas.layers)
    assert filters == tuple(f is not None for f in gas.filters) == (True, True, drag_averaging == "length")
    assert gas.band > 0
    band = memory.gas_band_bytes(s.model.scene)
    assert band == 8 * (gas.band + 2)
    assert per_cell == memory.gas_cell_bytes(s.model.features, gas.layers, filters, tube_shape == "cut") + band


def test_the_band_is_counted_as_the_cpus_before_taichi_starts(monkeypatch):
    """`tidem check` estimates a scene before Taichi starts: a thin grid's direct-solve band then counts as on the CPU
    (fluidized_tube's 20 x 1 x 50 cells: half-bandwidth 20), and not at all once a GPU runs."""
    import tidem.runtime.startup as startup
    raw = make_scene(gas={"density": 1.2, "viscosity": 1.8e-5, "cell_size": 0.004, "inlet_velocity": 1.0},
                     domain={"min": [0, 0, 0], "max": [0.08, 0.004, 0.2], "walls": "auto"})
    raw["particles"][0].update(diameter={"value": 0.001}, positions=[[0.04, 0.002, 0.1]])
    scene = validate(raw).scene
    monkeypatch.setattr(startup, "_current", None)
    assert memory.gas_band_bytes(scene) == 8 * (20 + 2)
    monkeypatch.setattr(startup, "_current", ("cuda", "float64", 1))
    assert memory.gas_band_bytes(scene) == 0
