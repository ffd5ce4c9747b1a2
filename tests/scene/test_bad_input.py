"""Bad scene input: exit code 2, one message naming file, key path and fix; never a traceback."""

import tomllib

import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.scene.load import SceneError, resolve

runner = CliRunner()


def impact_scene(tmp_path, edit):
    """The shipped impact scene with `edit(raw)` applied, written as TOML to tmp_path."""
    raw = tomllib.loads(resolve("sphere_impact").read_text())
    edit(raw)
    path = tmp_path / "bad.toml"
    path.write_text(to_toml(raw))
    return path


def to_toml(d, prefix=""):
    """A tiny TOML writer, enough for the test scenes (tables, arrays of tables, scalars)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return repr(v)

    lines, tables = [], []
    for k, v in d.items():
        if isinstance(v, dict):
            tables.append((k, v))
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {value(v)}")
    out = "\n".join(lines) + "\n"
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, list):
            for item in v:
                out += f"\n[[{name}]]\n" + "\n".join(f"{a} = {value(b)}" for a, b in item.items()) + "\n"
        elif all(isinstance(x, dict) for x in v.values()) and v:
            out += to_toml(v, name)
        else:
            out += f"\n[{name}]\n" + "\n".join(f"{a} = {value(b)}" for a, b in v.items()) + "\n"
    return out


def run_check(path, *extra):
    result = runner.invoke(app, ["check", str(path), *extra])
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result


@pytest.mark.parametrize(
    "edit, expected",
    [
        (lambda r: r["particles"][0]["diameter"].update(value=-0.0191),
         "particles[0].diameter.value: must be > 0 (got -0.0191)"),
        (lambda r: r["materials"]["sus304"].update(youngs_modulus="184 GPa"),
         "materials.sus304.youngs_modulus: expected a number, got the text '184 GPa'; units are SI: write 1.84e+11"),
        (lambda r: r["particles"][0]["diameter"].update(value="19.1 mm"),
         "write 0.0191"),
        (lambda r: r["materials"]["sus304"].update(densty=7800.0),
         "materials.sus304: unknown key 'densty'; did you mean 'density'?"),
        (lambda r: r.update(tubes=[{"center": [0.0, 0.0, 0.0], "diameter": 0.02},
                                   {"center": [0.0, 0.0, 0.0], "diameter": -0.027}]),
         "tubes[1].diameter: must be > 0 (got -0.027)"),
        (lambda r: r.update(tubes=[{"center": [0.2, 0.0, 0.0], "diameter": 0.027}]),
         "tubes[0] lies outside the domain"),
        (lambda r: r["particles"][0].update(material="steel"),
         "particles[0].material: no material named 'steel'; defined: sus304"),
        (lambda r: r["contact"].update(model="hooke"),
         "contact.model: input should be 'hertz_mindlin', 'linear', 'hysteretic' or 'none' (got 'hooke')"),
        (lambda r: r["numerics"].update(dt=1e-4),
         "numerics.dt: 0.0001 s is above the stability limit"),
        (lambda r: r["particles"][0]["positions"].__setitem__(0, [0.5, 0.0, 0.0]),
         "particles[0].positions[0]: [0.5, 0.0, 0.0] lies outside the domain"),
        (lambda r: r["domain"].update(max=[0.05, 0.2, -0.06]),
         "domain: max[2] must be greater than min[2]"),
        (lambda r: r.update(particles=[]),
         "particles: needs at least 1 item (got the list [])"),
        (lambda r: r["particles"][0].update(positions=[], velocities=[]),
         "particles[0]: 'positions' is empty: give at least one [x, y, z], or remove the group"),
        (lambda r: r["particles"][0].update(fixed="yes"),
         "particles[0].fixed: expected true or false, got 'yes'; write true or false (no quotes)"),
        (lambda r: r["particles"][0].update(fixed=1),
         "particles[0].fixed: expected true or false, got 1"),
        (lambda r: r["particles"][0].update(seed=True),
         "particles[0].seed: expected a whole number, got true"),
        (lambda r: r["particles"][0].update(coarse_grain=True),
         "particles[0].coarse_grain: expected a number, got true"),
        (lambda r: r.update(output={"snapshots": "40"}),
         "output.snapshots: expected a number, got the text '40'"),
        (lambda r: r["heat"].update(initial_temperature=-5),
         "heat.initial_temperature: must be > 0 (got -5); temperatures are in K (-5 °C is 268.15 K)"),
        (lambda r: r.update(reactions=[{"type": "burn"}]),
         "reactions[0]: type must be one of char_combustion, polymerization, sublimation (got 'burn')"),
        (lambda r: r.update(reactions=[{"rate": 1.0}]),
         "reactions[0]: type must be one of char_combustion, polymerization, sublimation (got nothing)"),
        (lambda r: r.update(outlet={"type": "moving_plate", "speed": 0.01}),
         "outlet.stop_height: -0.05 is not below the plate's start height -0.05"),
        (lambda r: r.pop("heat"),
         "particles[0].temperature: temperatures need a [heat] table"),
        (lambda r: r.pop("heat"),
         "observables: 'impact_heat' needs [heat]"),
        (lambda r: r["materials"]["sus304"].pop("conductivity"),
         "materials.sus304.conductivity: required with [heat]"),
        (lambda r: r["particles"][0].update(diameter={"distribution": "gauss", "value": 0.01}),
         "distribution must be one of mono, uniform, normal, lognormal (got 'gauss')"),
        (lambda r: r.update(tubes=[{"center": [0.0, 0.15, 0.0], "axis": "x", "diameter": 0.02, "temperature": 400.0,
                                    "heat_flux": 1000.0}]),
         "tubes[0]: give either 'temperature' (fixed wall temperature) or 'heat_flux' (heated foil), not both"),
        (lambda r: (r.pop("heat"), r["particles"][0].pop("temperature"),
                    r.update(tubes=[{"center": [0.0, 0.15, 0.0], "axis": "x", "diameter": 0.02, "heat_flux": 1000.0}])),
         "tubes[0].heat_flux: temperatures need a [heat] table"),
        (lambda r: r.update(tubes=[{"center": [0.0, 0.15, 0.0], "axis": "x", "diameter": 0.02, "heat_flux": 1000.0,
                                    "foil_heat_capacity": 1e-9}]),
         "tubes[0].foil_heat_capacity: the explicit foil update needs dt <="),
        (lambda r: r.update(walls=[{"point": [0.0, 0.0, -0.05], "normal": [0.0, 1.0, 1.0], "heat_flux": 500.0}]),
         "walls[0]: a wall with 'heat_flux' needs a normal along x, y or z"),
        (lambda r: r["heat"].update(radiation=True),
         "materials.sus304.emissivity: required with heat.radiation = true (used by particles[0], particles[1])"),
    ],
)
def test_bad_input_is_one_clear_message(tmp_path, edit, expected):
    path = impact_scene(tmp_path, edit)
    result = run_check(path)
    assert result.exit_code == 2, result.output
    assert expected in result.output
    assert str(path) in result.output
    assert "Traceback" not in result.output


def test_all_errors_reported_together(tmp_path):
    def edit(r):
        r["materials"]["sus304"]["density"] = -1.0
        r["particles"][0]["diameter"]["value"] = 0.0
        r["numerics"]["t_end"] = "1 s"

    result = run_check(impact_scene(tmp_path, edit))
    assert result.exit_code == 2
    assert "3 errors" in result.output
    for key in ("materials.sus304.density", "particles[0].diameter.value", "numerics.t_end"):
        assert key in result.output


def test_distribution_defaults_to_mono(tmp_path):
    path = impact_scene(tmp_path, lambda r: r["particles"][0]["diameter"].pop("distribution"))
    assert run_check(path).exit_code == 0


def test_a_plain_number_is_one_diameter(tmp_path):
    from tidem.scene.load import load

    path = impact_scene(tmp_path, lambda r: r["particles"][0].update(diameter=0.0191))
    assert load(str(path)).scene.particles[0].diameter.value == 0.0191
    path = impact_scene(tmp_path, lambda r: r["particles"][0].update(diameter=-0.0191))
    assert "particles[0].diameter.value: must be > 0 (got -0.0191)" in run_check(path).output


def test_forced_dt_is_accepted(tmp_path):
    path = impact_scene(tmp_path, lambda r: r["numerics"].update(dt=1e-4, force_dt=True))
    assert run_check(path).exit_code == 0


def test_set_override_is_validated():
    result = runner.invoke(app, ["check", "sphere_impact", "--set", "materials.sus304.restitution=1.5"])
    assert result.exit_code == 2
    assert "materials.sus304.restitution: must be <= 1" in result.output
    result = runner.invoke(app, ["check", "sphere_impact", "--set", "numerics.dt_fraction=0.05"])
    assert result.exit_code == 0, result.output


def test_set_one_past_the_last_item_adds_one():
    from tidem.scene.load import apply_override

    raw = {"walls": []}
    apply_override(raw, "walls[0].point=[0.0, 0.0, -0.04]")
    apply_override(raw, "walls[0].normal=[0, 0, 1]")
    apply_override(raw, "walls[1]={ point = [0.0, 0.0, 0.04], normal = [0, 0, -1] }")
    assert raw["walls"] == [{"point": [0.0, 0.0, -0.04], "normal": [0, 0, 1]},
                            {"point": [0.0, 0.0, 0.04], "normal": [0, 0, -1]}]
    with pytest.raises(ValueError, match=r"index 3 is out of range \(walls has 2 items, \[0\] to \[1\]; \[2\] adds"):
        apply_override(raw, "walls[3].point=[0, 0, 0]")
    result = runner.invoke(app, ["check", "sphere_impact", "--set", "walls[0].point=[0.0, 0.0, -0.04]",
                                 "--set", "walls[0].normal=[0, 0, 1]"])
    assert result.exit_code == 0 and "walls: walls[0]; tubes: 0" in result.output, result.output


def test_unknown_scene_name_lists_shipped():
    """A scene that cannot be found is one line naming it, not a count of errors in a scene never read."""
    result = runner.invoke(app, ["check", "no_such_scene"])
    assert result.exit_code == 2
    assert result.output.startswith("no_such_scene: no such file, and no shipped scene of that name")
    assert "sphere_impact.toml" in result.output and "error" not in result.output


def test_invalid_toml(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[domain\nmin = 1")
    result = run_check(path)
    assert result.exit_code == 2 and result.output.startswith(f"{path}: not valid TOML")


@pytest.mark.parametrize("args, expected", [
    (["scene", "sphere_impact", "--arch", "tpu"], "--arch tpu: choose cpu, cuda, vulkan or auto"),
    (["scene", "sphere_impact", "--t-end", "-1"], "--t-end -1.0: the end time must be a finite number > 0 s"),
    (["scene", "sphere_impact", "--set", "numerics.t_end"], "expected KEY=VALUE"),
    (["bench", "--precision", "half"], "--precision half: choose float32, float64, mixed, both or all"),
    (["bench", "--arch", "gpu"], "--arch gpu: choose cpu, cuda or vulkan"),
    (["check", ""], "no scene given: name a scene file or a shipped scene (char_combustion.toml"),
])
def test_bad_command_line_options(args, expected):
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert expected in result.output and "Traceback" not in result.output


def test_a_shipped_name_is_found_beside_an_output_folder_of_that_name(tmp_path, monkeypatch):
    """`tidem scene sphere_impact --out sphere_impact` leaves a folder named like the scene; the next
    `tidem scene sphere_impact` from there still means the shipped scene. A folder holding scene
    files stays an error naming them."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sphere_impact").mkdir()
    assert resolve("sphere_impact").name == "sphere_impact.toml"
    assert resolve("sphere_impact").parent != tmp_path / "sphere_impact"
    (tmp_path / "sphere_impact" / "mine.toml").write_text("")
    with pytest.raises(SceneError, match="mine.toml"):
        resolve("sphere_impact")


def test_check_notes_what_a_run_would_not_do_as_asked():
    """Output asked beyond one snapshot a step or past t_end, a run of 1e12 steps, a gas grid of one cell
    up: each gets a note (exit 0: the scene is valid)."""
    for sets, note in ((["output.snapshots=100000000"], "note: 100000000 snapshots asked for, but a run writes at "
                        "most one a step: 1122 in 1121 steps"),
                       (["output.interval=10.0"], "note: output.interval (10 s) is longer than t_end (0.0012 s)"),
                       (["numerics.dt=1e-15", "numerics.force_dt=true"], "note: 1.2e+12 steps to t_end")):
        result = runner.invoke(app, ["check", "sphere_impact", *[a for s in sets for a in ("--set", s)]])
        assert result.exit_code == 0 and note in result.output, result.output
    result = runner.invoke(app, ["check", "char_combustion", "--set", "gas.cell_size=10.0"])
    assert result.exit_code == 0 and "note: the gas grid has 1 cell(s) up" in result.output, result.output
    assert "note: the gas grid has one cell across x between walls" in result.output
    assert "note:" not in runner.invoke(app, ["check", "char_combustion"]).output
    result = runner.invoke(app, ["check", "fluidized_tube", "--set", "heat.initial_temperature=20"])
    assert result.exit_code == 0 and ("note: heat.initial_temperature = 20 K; temperatures are in kelvin (20 °C "
                                      "would be 293.15 K)") in result.output, result.output
