"""The Ergun integrals that the gas tests take as references (`tidem.analytic.ergun`)."""

import math

import numpy as np
import pytest

from tidem.analytic.ergun import ergun_gradient, tapered_bed_ergun, whole_bed_ergun

MU, RHO, D = 1.8e-5, 1.2, 0.001


def test_a_tapered_bed_of_constant_cross_section_is_the_whole_bed_integral():
    z = np.random.default_rng(1).uniform(0.0005, 0.02, 3000)
    area, u = 1e-4, 0.3
    straight = whole_bed_ergun(z, D, area, 0.03, u, MU, RHO, D / 2)
    assert tapered_bed_ergun(z, D, lambda s: np.full_like(s, area), 0.03, u * area, MU, RHO, D / 2) == \
        pytest.approx(straight, rel=1e-12)


def test_a_wedge_of_uniform_layers_integrates_the_viscous_term_as_a_logarithm():
    """Layers of grains one diameter apart whose count grows with the wedge's width A(z) = A0 (1 + z / L), so every
    layer has the same voidage: the viscous part of Ergun's gradient goes as 1 / A, and its integral over the bed
    is the layer sum of 150 (1 - e)^2 mu Q / (e^3 d^2 A0 (1 + z_k / L)) d, close to the logarithm's
    L ln(1 + H / L) / A0 for many layers."""
    L, A0, H = 0.05, 1e-4, 0.04
    layers = int(H / D)
    per_area = 9.5e5  # grains per m^2 of a layer: a solid fraction pi D^2 / 6 * per_area = 0.497 over one diameter
    z = np.concatenate([np.full(int(round(per_area * A0 * (1 + (k + 0.5) * D / L))), (k + 0.5) * D)
                        for k in range(layers)])
    eps = 1.0 - per_area * math.pi * D**3 / 6 / D  # each layer's voidage over a slice one diameter high
    flow = 1e-7  # m^3/s: creeping flow, the inertial term under 1e-3 of the viscous one
    drop = tapered_bed_ergun(z, D, lambda s: A0 * (1 + s / L), H, flow, MU, RHO, D)
    viscous = 150 * (1 - eps) ** 2 * MU * flow / (eps**3 * D * D * A0) * L * math.log(1 + H / L)
    assert drop == pytest.approx(viscous, rel=0.01)
    assert drop > ergun_gradient(eps, flow / (A0 * (1 + H / L)), D, MU, RHO) * H, "the narrow end costs most"
