"""A corpus of malformed scenes, `--set` overrides and paths, as a hurried user types them:
each must exit with code 2 and one message that names the file (or option), the
key and the fix, with no traceback. One row per bad input; the CLI runs in-process."""

import os
import stat

import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app

runner = CliRunner()

TINY = """name = "tiny"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]

[materials.sand]
density = 2600.0
youngs_modulus = 1e7

[[particles]]
name = "bed"
material = "sand"
diameter = { value = 0.01 }
positions = [[0.05, 0.05, 0.05]]
"""
HEAT = "\n[heat]\ninitial_temperature = 300.0\n"
HEATED_SAND = TINY.replace("youngs_modulus = 1e7", "youngs_modulus = 1e7\nconductivity = 1.0\nheat_capacity = 800.0")
GAS = "\n[gas]\ncell_size = 0.03\n"


def tiny(old: str, new: str) -> str:
    """TINY with one piece of text replaced (the piece must be there)."""
    assert old in TINY
    return TINY.replace(old, new)


FILE = "{file}"
# (id, scene file content or None, command line with {file}, text the message must name (key), text of the fix)
CORPUS = [
    # syntax and encodings
    ("unclosed table", "[domain\nmin = 1\n", None, "not valid TOML", "docs/scenes.md"),
    ("json not toml", '{"domain": {"min": [0, 0, 0]}}', None, "not valid TOML", "docs/scenes.md"),
    ("duplicate key", tiny("max = [0.1", "min = [0.0, 0.0, 0.0]\nmax = [0.1"), None, "not valid TOML", "docs/scenes.md"),
    ("latin-1 text", tiny('name = "tiny"', 'name = "caf\u00e9"').encode("latin-1"), None, "not UTF-8 text",
     "save the file as UTF-8"),
    ("utf-16 text", TINY.encode("utf-16"), None, "saved as UTF-16", "save the file as UTF-8"),
    ("binary file", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe", None, "binary file", "give the scene's .toml file"),
    ("empty file", "", None, "domain: required key is missing", "add it"),
    ("string escape", tiny('name = "tiny"', 'name = "C:\\temp\\x"'), None, "not valid TOML", "docs/scenes.md"),
    # unknown and mistyped keys
    ("typo top-level table", tiny("[domain]", "[domian]"), None, "unknown key 'domian'", "did you mean 'domain'"),
    ("typo material key", tiny("youngs_modulus", "youngs_modulous"), None, "unknown key 'youngs_modulous'",
     "did you mean 'youngs_modulus'"),
    ("capitalised key", tiny("density", "Density"), None, "materials.sand: unknown key 'Density'",
     "did you mean 'density'"),
    ("particles as a table", tiny("[[particles]]", "[particles]"), None, "particles", "[[particles]]"),
    ("materials as a list", tiny("[materials.sand]", "[[materials]]\nname = 'sand'"), None, "materials",
     "[materials.sand]"),
    # wrong types and shapes
    ("number as text", tiny("density = 2600.0", 'density = "2600"'), None, "materials.sand.density",
     "write a plain number"),
    ("modulus with unit", tiny("youngs_modulus = 1e7", 'youngs_modulus = "10 MPa"'), None,
     "materials.sand.youngs_modulus", "units are SI: write 1e+07"),
    ("diameter in mm", tiny("value = 0.01", 'value = "10 mm"'), None, "particles[0].diameter.value", "write 0.01"),
    ("temperature in celsius", HEATED_SAND.replace('name = "bed"', 'name = "bed"\ntemperature = "20 C"') + HEAT, None,
     "particles[0].temperature", "kelvin: write 293.15"),
    ("point of two numbers", tiny("min = [0.0, 0.0, 0.0]", "min = [0.0, 0.0]"), None, "domain.min", "3 numbers"),
    ("point of four numbers", tiny("max = [0.1, 0.1, 0.1]", "max = [0.1, 0.1, 0.1, 0.1]"), None, "domain.max",
     "3 numbers"),
    ("flat positions", tiny("[[0.05, 0.05, 0.05]]", "[0.05, 0.05, 0.05]"), None, "particles[0].positions[0]",
     "3 numbers"),
    ("fractional count", tiny("positions = [[0.05, 0.05, 0.05]]",
                              "region = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.1] }\ncount = 10.5"), None,
     "particles[0].count", "write an integer"),
    ("boolean as number", tiny('name = "bed"', 'name = "bed"\nfixed = 2'), None, "particles[0].fixed",
     "true or false"),
    ("list for a number", tiny("density = 2600.0", "density = [2600.0, 2500.0]"), None, "materials.sand.density",
     "one number"),
    ("negative seed", tiny('name = "bed"', 'name = "bed"\nseed = -1'), None, "particles[0].seed", "must be >= 0"),
    # NaN and inf
    ("nan density", tiny("density = 2600.0", "density = nan"), None, "materials.sand.density", "must be"),
    ("inf modulus", tiny("youngs_modulus = 1e7", "youngs_modulus = inf"), None, "materials.sand.youngs_modulus",
     "must be a finite number"),
    ("nan gravity", tiny("max = [0.1, 0.1, 0.1]", "max = [0.1, 0.1, 0.1]\ngravity = [0.0, 0.0, nan]"), None,
     "domain.gravity", "must be a finite number"),
    ("inf position", tiny("[[0.05, 0.05, 0.05]]", "[[0.05, inf, 0.05]]"), None, "particles[0].positions[0]",
     "must be a finite number"),
    # out-of-range physics
    ("restitution above one", tiny("youngs_modulus = 1e7", "youngs_modulus = 1e7\nrestitution = 1.5"), None,
     "materials.sand.restitution", "must be <= 1"),
    ("poisson ratio one half", tiny("youngs_modulus = 1e7", "youngs_modulus = 1e7\npoisson_ratio = 0.5"), None,
     "materials.sand.poisson_ratio", "must be < 0.5"),
    ("negative friction", tiny("youngs_modulus = 1e7", "youngs_modulus = 1e7\nfriction = -0.1"), None,
     "materials.sand.friction", "must be >= 0"),
    ("step above the stability limit", TINY + "\n[numerics]\ndt = 1.0\n", None, "numerics.dt", "use dt <="),
    ("zero overlap limit", TINY + "\n[numerics]\nmax_overlap = 0.0\n", None, "numerics.max_overlap", "must be > 0"),
    ("far too soft", tiny("youngs_modulus = 1e7", "youngs_modulus = 1.0"), None, "materials.sand.youngs_modulus",
     "use youngs_modulus >="),
    # geometry that contradicts itself
    ("max below min", tiny("max = [0.1, 0.1, 0.1]", "max = [0.1, -0.1, 0.1]"), None, "domain",
     "max[1] must be greater than min[1]"),
    ("position outside the domain", tiny("[[0.05, 0.05, 0.05]]", "[[0.5, 0.05, 0.05]]"), None,
     "particles[0].positions[0]", "lies outside the domain"),
    ("region outside the domain", tiny("positions = [[0.05, 0.05, 0.05]]",
                                       "region = { min = [0.0, 0.0, 0.0], max = [0.2, 0.1, 0.1] }"), None,
     "particles[0].region", "reaches outside the domain"),
    ("region too small for count", tiny("positions = [[0.05, 0.05, 0.05]]",
                                        "region = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.02] }\ncount = 500"),
     None, "particles[0]", "enlarge 'region' or lower 'count'"),
    ("two particles at one point", tiny("[[0.05, 0.05, 0.05]]", "[[0.05, 0.05, 0.05], [0.05, 0.05, 0.05]]"), None,
     "particles[0].positions[0] and particles[0].positions[1]", "at least 0.01 m apart"),
    ("particle in the floor", tiny("[[0.05, 0.05, 0.05]]", "[[0.05, 0.05, 0.001]]"), None,
     "particles[0].positions[0]", "move it clear of the surface"),
    ("particle inside a tube", TINY + "\n[[tubes]]\ncenter = [0.05, 0.0, 0.05]\ndiameter = 0.02\n", None,
     "particles[0].positions[0]", "move it clear of the surface"),
    ("overlapping fills", tiny("positions = [[0.05, 0.05, 0.05]]",
                               "region = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.05] }")
     + '\n[[particles]]\nname = "top"\nmaterial = "sand"\ndiameter = { value = 0.01 }\n'
       "region = { min = [0.0, 0.0, 0.03], max = [0.1, 0.1, 0.1] }\n", None, "particles[1].region",
     "disjoint"),
    ("tube outside the domain", TINY + "\n[[tubes]]\ncenter = [0.05, 0.3, 0.3]\naxis = 'x'\ndiameter = 0.02\n", None,
     "tubes[0] lies outside the domain", "move its center"),
    ("unknown material", tiny('material = "sand"', 'material = "snad"'), None, "particles[0].material",
     "defined: sand"),
    ("wall on a periodic axis", tiny("max = [0.1, 0.1, 0.1]", "max = [0.1, 0.1, 0.1]\nperiodic = ['x']\n"
                                     "walls = ['x-', 'z-']"), None, "domain.walls", "remove one of them"),
    ("zero wall normal", TINY + "\n[[walls]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]\n", None,
     "walls[0]", "normal must not be the zero vector"),
    # sizes that cannot fit in memory
    ("fill of tiny particles", tiny("value = 0.01", "value = 1e-5").replace(
        "positions = [[0.05, 0.05, 0.05]]", "region = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.1] }"), None,
     "particles[0].region", "larger particles"),
    ("a trillion poured", tiny("positions = [[0.05, 0.05, 0.05]]",
                               "count = 1000000000000\npour = { region = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.1] }"
                               ", rate = 1000.0 }"), None, "particles[0].count", "use fewer particles"),
    ("fine gas grid in a huge box", tiny("max = [0.1, 0.1, 0.1]", "max = [1000.0, 1000.0, 1000.0]") + GAS, None,
     "gas.cell_size", "use larger gas cells"),
    ("huge count, readable figures", tiny("positions = [[0.05, 0.05, 0.05]]",
                                          "count = 99999999999999999999\npour = { region = { min = [0.0, 0.0, 0.0], "
                                          "max = [0.1, 0.1, 0.1] }, rate = 1000.0 }"), None, "e+", "use fewer"),
    # --set overrides
    ("set unknown key", TINY, ["check", FILE, "--set", "numerics.dtt=1e-6"], "numerics: unknown key 'dtt'",
     "did you mean 'dt'"),
    ("set into a list without index", TINY, ["check", FILE, "--set", "particles.count=3"], "particles",
     "write particles[0].count"),
    ("set index out of range", TINY, ["check", FILE, "--set", "particles[3].count=3"], "particles[3].count",
     "[0] to [0]; [1] adds an item"),
    ("set without value", TINY, ["check", FILE, "--set", "numerics.t_end"], "--set", "expected KEY=VALUE"),
    ("set empty key", TINY, ["check", FILE, "--set", "=3"], "--set", "write KEY=VALUE"),
    ("set with unit", TINY, ["check", FILE, "--set", "numerics.t_end=1s"], "numerics.t_end", "units are SI: write 1"),
    ("set nan", TINY, ["check", FILE, "--set", "numerics.t_end=nan"], "numerics.t_end", "must be"),
    ("set into a value", TINY + "\n[numerics]\nt_end = 1.0\n", ["check", FILE, "--set", "numerics.t_end.max=3"], "numerics.t_end",
     "set numerics.t_end=VALUE itself"),
    ("set tiny fill on a shipped scene", None, ["check", "moving_bed_tubes", "--set",
                                                "particles[0].diameter.value=1e-5"],
     "particles[0]", "use fewer particles"),
    # paths and options
    ("scene is a folder", None, ["check", "{dir}"], "this is a folder", "give the .toml file"),
    ("no such scene", None, ["check", "{dir}/nope.toml"], "no such file", "shipped scenes:"),
    ("out is a file", TINY, ["scene", FILE, "--out", FILE, "--no-render", "--quiet"], "--out",
     "a file of that name exists"),
    ("out under a file", TINY, ["scene", FILE, "--out", FILE + "/run", "--no-render", "--quiet"], "--out",
     "choose another output folder"),
    ("sweep into a file", TINY, ["sweep", FILE, "--vary", "numerics.t_end=0.1,0.2", "--out", FILE + "/sweep"],
     "--out", "choose another output folder"),
    ("resume without checkpoint", TINY, ["scene", FILE, "--resume", "{dir}", "--no-render", "--quiet"], "--resume",
     "a run writes one"),
    ("corrupt checkpoint", TINY, ["scene", FILE, "--resume", "{dir}/run", "--no-render", "--quiet"], "--resume",
     "unreadable checkpoint"),
    ("render a folder with broken run.json", None, ["render", "{dir}/run"], "run.json", "run the scene again"),
    ("infinite end time", TINY, ["scene", FILE, "--t-end", "inf"], "--t-end", "finite number > 0"),
]


@pytest.mark.parametrize("content, argv, key, fix", [row[1:] for row in CORPUS], ids=[row[0] for row in CORPUS])
def test_bad_input_exits_2_naming_file_key_and_fix(tmp_path, content, argv, key, fix):
    path = tmp_path / "scene.toml"
    if content is not None:
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "checkpoint.npz").write_bytes(b"PK\x03\x04 cut short")
    (tmp_path / "run" / "run.json").write_text('{"scene": "tiny", ')
    (tmp_path / "run" / "snapshots.pvd").write_text("")
    argv = [a.replace(FILE, str(path)).replace("{dir}", str(tmp_path)) for a in (argv or ["check", FILE])]
    result = runner.invoke(app, argv)
    out = result.output
    assert result.exit_code == 2, out
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    if not key.startswith("--"):  # a scene error names the scene file; an option error the option
        named = [a for a in argv[1:] if not a.startswith("-")][0]
        assert named in out or os.path.basename(named) in out, out
    assert key in out, out
    assert fix in out, out
    assert "Traceback" not in out


def test_the_corpus_is_large_and_distinct():
    assert len(CORPUS) >= 40
    assert len({row[0] for row in CORPUS}) == len(CORPUS)


def test_an_unreadable_folder_for_out_is_refused(tmp_path):
    if os.geteuid() == 0:
        pytest.skip("root writes anywhere")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    path = tmp_path / "scene.toml"
    path.write_text(TINY)
    result = runner.invoke(app, ["scene", str(path), "--out", str(locked / "run"), "--no-render", "--quiet"])
    assert result.exit_code == 2 and "cannot write there" in result.output
