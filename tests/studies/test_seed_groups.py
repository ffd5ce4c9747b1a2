"""`tidem tradeoff`'s seed groups (`tidem.studies.seed_groups`): variants that differ only in a seed,
their mean, range, deviation from the reference group and speed-up, on made-up results (no runs)."""

import csv

import pytest

from tidem.studies.seed_groups import is_seed, seed_groups, write_groups


def result(index, k, seed, height, alpha, wall, status="finished"):
    return {"index": index, "overrides": [f"particles[0].coarse_grain={k}", f"particles[0].seed={seed}"],
            "status": status, "wall_s": wall, "observables": {"bed_height_mean_m": height, "alpha": alpha,
                                                              "note": "text is no column"}}


def test_seeds_of_a_variant_are_one_group_against_the_reference_group(tmp_path):
    results = [result(0, 1, 1, 0.060, 150.0, 100.0), result(1, 1, 2, 0.064, 160.0, 120.0),
               result(2, 3, 1, 0.054, 140.0, 4.0), result(3, 3, 2, 0.056, 145.0, 6.0),
               result(4, 3, 3, 0.0, 0.0, 1.0, status="stopped")]
    groups, ref = seed_groups(results, reference=1)
    assert ref == 0 and [g.label for g in groups] == ["particles[0].coarse_grain=1", "particles[0].coarse_grain=3"]
    assert [len(g.runs) for g in groups] == [2, 2], "a run that did not finish is left out"
    write_groups(groups, ref, tmp_path)
    with open(tmp_path / "tradeoff_groups.csv") as fh:
        rows = list(csv.DictReader(fh))
    k3 = rows[1]
    assert float(k3["bed_height_mean_m_mean"]) == pytest.approx(0.055)
    assert (float(k3["bed_height_mean_m_min"]), float(k3["bed_height_mean_m_max"])) == (0.054, 0.056)
    assert float(k3["bed_height_mean_m_deviation"]) == pytest.approx((0.055 - 0.062) / 0.062)
    assert float(k3["alpha_deviation"]) == pytest.approx((142.5 - 155.0) / 155.0)
    assert float(k3["speed_up"]) == pytest.approx(110.0 / 5.0)
    assert float(rows[0]["speed_up"]) == 1.0 and float(rows[0]["alpha_deviation"]) == 0.0
    assert "note_mean" not in k3
    md = (tmp_path / "tradeoff_groups.md").read_text()
    assert ("| particles[0].coarse_grain=3 | 2 | 5 | 22x | 142.5 [140, 145] (-8.1 %) | 0.055 [0.054, 0.056] (-11.3 %) |") in md
    assert (tmp_path / "tradeoff_groups.png").stat().st_size > 10_000


def test_nothing_to_group_without_a_seed_or_with_one_run_per_group():
    assert is_seed("particles[2].seed=4") and not is_seed("particles[0].seeds=1") and not is_seed("seeding=1")
    plain = [{**result(i, k, 1, 0.06, 150.0, 10.0), "overrides": [f"particles[0].coarse_grain={k}"]}
             for i, k in enumerate((1, 3))]
    assert seed_groups(plain, reference=0) is None
    one_each = [result(i, k, 1, 0.06, 150.0, 10.0) for i, k in enumerate((1, 3))]
    assert seed_groups(one_each, reference=0) is None
