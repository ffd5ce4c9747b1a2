"""`tidem tradeoff` and `tidem sweep` on a local Dask cluster of 2 workers, and the
step-halving loop, on the two-sphere impact (seconds per variant); observables come from the
registry (`tidem.results.observables`) through each run's run.json."""

import csv

import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.results.observables import flatten
from tidem.studies.tradeoff import agree, parse_vary, variants, with_errors, write_report

runner = CliRunner()


def test_vary_makes_every_combination():
    todo = variants(parse_vary(["a.b=1,2", "c=x,y,z"]), ["d=0"])
    assert len(todo) == 6
    assert todo[0].overrides == ["d=0", "a.b=1", "c=x"] and todo[-1].overrides == ["d=0", "a.b=2", "c=z"]
    with pytest.raises(ValueError, match="KEY=VALUE1,VALUE2"):
        parse_vary(["numerics.dt_fraction"])


def test_agree_is_relative():
    assert agree({"a": 1.0, "b": 2.0}, {"a": 1.005, "b": 2.0}, 0.01)
    assert not agree({"a": 1.0}, {"a": 1.02}, 0.01)
    assert not agree({"a": 1.0}, {"b": 1.0}, 0.01), "nothing to compare is not agreement"


def test_pressure_fluctuation_and_mean_bed_height_reach_the_table(tmp_path):
    """Two variants' run.json observables as run_variant reads them: the new columns get values
    and errors; a frequency left out (null, with its note) is no column, the note no number."""
    def observed(std, freq, mean):
        note = {} if freq else {"pressure_drop_frequency_note": "fewer than 5 periods"}
        return {"pressure_fluctuation": {"pressure_drop_std_Pa": std, "pressure_drop_frequency_Hz": freq, **note},
                "bed_height": {"bed_height_m": 0.05, "bed_height_mean_m": mean}}

    results = [{"index": i, "overrides": [f"v={i}"], "status": "finished", "wall_s": 10.0 * (i + 1),
                "particle_steps_per_s": 1e6, "steps": 100 * (i + 1), "dt_s": 1e-5, "observables": flatten(obs)}
               for i, obs in enumerate([observed(80.0, None, 0.060), observed(78.0, 4.2, 0.058)])]
    results, ref = with_errors(results)
    assert ref == 1
    write_report(results, ref, tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "tradeoff.csv")))
    assert float(rows[0]["error_pressure_drop_std_Pa"]) == pytest.approx(2.0 / 78.0)
    assert float(rows[0]["error_bed_height_mean_m"]) == pytest.approx(0.002 / 0.058)
    assert rows[0]["pressure_drop_frequency_Hz"] == "" and float(rows[1]["pressure_drop_frequency_Hz"]) == 4.2
    assert "pressure_drop_frequency_note" not in rows[0]


def test_tradeoff_on_two_local_workers(tmp_path):
    out = tmp_path / "to"
    result = runner.invoke(app, ["tradeoff", "sphere_impact", "--vary", "numerics.dt_fraction=0.05,0.4",
                                 "--workers", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(open(out / "tradeoff.csv")))
    assert [r["status"] for r in rows] == ["finished", "finished"]
    # the reference is the finer step; the coarse step's contact time differs by a measurable amount
    assert float(rows[0]["error_contact_time_s"]) == 0.0
    assert 1e-4 < float(rows[1]["error_contact_time_s"]) < 0.05
    assert float(rows[1]["dt_s"]) == pytest.approx(8 * float(rows[0]["dt_s"]))
    assert (out / "tradeoff.md").read_text().count("| finished |") == 2
    assert (out / "tradeoff.png").stat().st_size > 10_000
    assert (out / "variant_00" / "run.json").exists() and (out / "variant_01" / "run.json").exists()


def test_sweep_writes_one_folder_per_variant(tmp_path):
    out = tmp_path / "sw"
    result = runner.invoke(app, ["sweep", "sphere_impact", "--vary", "materials.sus304.restitution=0.5,0.9",
                                 "--workers", "2", "--threads", "1", "--observables", "kinetic_energy,restitution",
                                 "--out", str(out)])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(open(out / "sweep.csv")))
    assert "contact_time_s" not in rows[0], "--observables replaces the scene's list"
    ke = [float(r["kinetic_energy_J"]) for r in rows]
    assert ke[0] < ke[1], "less restitution keeps less kinetic energy"
    assert [float(r["restitution"]) for r in rows] == [pytest.approx(0.5, rel=0.01), pytest.approx(0.9, rel=0.01)]


def test_halving_converges_and_bad_keys_are_refused(tmp_path):
    result = runner.invoke(app, ["tradeoff", "sphere_impact", "--halve", "numerics.dt_fraction", "--tol", "0.02",
                                 "--out", str(tmp_path / "h")])
    assert result.exit_code == 0, result.output
    assert "converged: numerics.dt_fraction = " in result.output
    bad = runner.invoke(app, ["tradeoff", "sphere_impact", "--halve", "numerics.precision"])
    assert bad.exit_code == 2 and "needs a positive number" in bad.output
    bad = runner.invoke(app, ["tradeoff", "sphere_impact", "--vary", "numerics.dt_fraction=0.1,7"])
    assert bad.exit_code == 2 and "variant 1" in bad.output
    bad = runner.invoke(app, ["tradeoff", "sphere_impact", "--vary", "numerics.dt_fraction=0.1,0.2", "--set", "observables=[]"])
    assert bad.exit_code == 2 and "declares no observables" in bad.output
