"""The per-phase profile of a run: run.json's `profile` accounts for the loop's wall time, and
`tidem bench --profile SCENE` prints the table (phases named in `tidem.runtime.phases.PHASES`)."""

import json

import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.runtime.phases import PHASES, SAMPLE_EVERY, PhaseTimer, sampled_step

runner = CliRunner()


def test_laps_accumulate_per_phase_and_total():
    timer = PhaseTimer()
    t = timer.lap("contact forces", 0.0)
    timer.lap("kick", t - 0.5)
    table = timer.table(steps=10)
    assert table["kick"]["seconds"] == pytest.approx(0.5, abs=1e-3)
    assert table["total"]["seconds"] == pytest.approx(table["kick"]["seconds"] + table["contact forces"]["seconds"])
    assert table["kick"]["ms_per_step"] == pytest.approx(50.0, abs=0.1)
    assert set(table) <= set(PHASES) | {"total"}


def test_a_sampled_profile_shares_the_steps_time_out_as_its_sampled_steps_do():
    """A GPU run's profile (`tidem.runtime.phases`): every step's time booked where the host happened to wait
    (here all under "kick-drift") is shared out among the phases as the sampled steps share theirs;
    output keeps its own time, and the total is unchanged."""
    timer = PhaseTimer(sample_every=4)
    for step in range(1, 9):
        t = timer.begin_step(step)
        if timer._sampling:  # a sampled step: 1 s of forces, 3 s of pressure solve
            t = timer.lap("forces and kick", t - 1.0)
            timer.lap("pressure solve", t - 3.0)
        else:
            timer.lap("kick-drift", t - 4.0)
    timer.lap("output", timer.begin_output() - 2.0)
    table = timer.table(steps=8)
    assert table["total"]["sampled_steps"] == 2
    assert table["total"]["seconds"] == pytest.approx(34.0, abs=1e-2)  # the laps' own wall time: under 1e-2 s on a loaded machine
    assert table["forces and kick"]["seconds"] == pytest.approx(8.0, abs=1e-2)
    assert table["pressure solve"]["seconds"] == pytest.approx(24.0, abs=1e-2)
    assert table["output"]["seconds"] == pytest.approx(2.0, abs=1e-2)
    assert "kick-drift" not in table


@pytest.mark.parametrize("every", [4, SAMPLE_EVERY])
def test_sampled_steps_are_spread_over_the_multiples_of_every_interval(every):
    """The steps a GPU run samples (`tidem.runtime.phases.sampled_step`) are one in `every`, and one in `every` of
    the steps of a phase that comes every k steps (the gas every coupling_interval, conduction every
    conduction_interval), for any k up to 50 within 5 % over 200 000 steps: every 16th step sampled
    the gas steps of a 20-step coupling 4x as often as they come (the multiples of 80), and the
    profile booked the gas at twice its time."""
    steps = range(1, 200_001)
    assert sum(sampled_step(s, every) for s in steps) / len(steps) == pytest.approx(1 / every, rel=0.01)
    for k in range(2, 51):
        multiples = range(k, 200_001, k)
        share = sum(sampled_step(s, every) for s in multiples) / len(multiples)
        assert share == pytest.approx(1 / every, rel=0.05), k


def test_run_json_profile_accounts_for_the_wall_time(tmp_path):
    out = tmp_path / "impact"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 0, result.output
    run = json.loads((out / "run.json").read_text())
    profile = run["profile"]
    assert {"forces and kick", "kick-drift", "output"} <= set(profile)
    # the phases cover the stepping loop: their sum is the loop's wall time less only the Python glue
    assert 0.8 * run["wall_s"] <= profile["total"]["seconds"] <= run["wall_s"]


def test_bench_profile_prints_the_phase_table_and_refuses_bad_counts(tmp_path):
    result = runner.invoke(app, ["bench", "--profile", "sphere_impact", "--steps", "50", "--warmup", "5",
                                 "--out", str(tmp_path / "p.json")])
    assert result.exit_code == 0, result.output
    assert "particle-steps/s" in result.output and "contact forces" in result.output
    saved = json.loads((tmp_path / "p.json").read_text())
    assert saved["steps"] == 50 and saved["profile"]["total"]["ms_per_step"] > 0
    bad = runner.invoke(app, ["bench", "--profile", "sphere_impact", "--steps", "0"])
    assert bad.exit_code == 2 and "--steps 0" in bad.output
