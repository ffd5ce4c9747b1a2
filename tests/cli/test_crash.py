"""The last line of defence of the CLI (`tidem.cli.commands.main`, `tidem.cli.crash`): an unexpected
exception prints one line naming a log file with the traceback and exits 70; Ctrl-C keeps its
own handling."""

import sys

import pytest

import tidem.scene.load
from tidem.cli import crash
from tidem.cli.commands import main


def fail_with(monkeypatch, exc):
    def boom(*args, **kwargs):
        raise exc
    monkeypatch.setattr(tidem.scene.load, "load", boom)
    monkeypatch.setattr(sys, "argv", ["tidem", "check", "sphere_impact"])


def test_an_unexpected_exception_is_one_line_and_a_log_file(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("TIDEM_LOG_DIR", str(tmp_path / "logs"))
    fail_with(monkeypatch, RuntimeError("boom in the loader"))
    with pytest.raises(SystemExit) as done:
        main()
    assert done.value.code == crash.INTERNAL_ERROR == 70
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "internal error: RuntimeError: boom in the loader" in err
    logs = list((tmp_path / "logs").glob("tidem-error-*.log"))
    assert len(logs) == 1 and str(logs[0]) in err
    text = logs[0].read_text()
    assert "Traceback" in text and "boom in the loader" in text and "command: tidem check sphere_impact" in text


def test_no_log_folder_still_gives_one_line(monkeypatch, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("TIDEM_LOG_DIR", str(blocker / "logs"))
    fail_with(monkeypatch, MemoryError())
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 70 and "ran out of memory" in err and "no log could be written" in err
    assert "Traceback" not in err


def test_ctrl_c_is_not_turned_into_an_internal_error(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("TIDEM_LOG_DIR", str(tmp_path / "logs"))
    fail_with(monkeypatch, KeyboardInterrupt())
    with pytest.raises((SystemExit, KeyboardInterrupt)) as done:
        main()
    assert getattr(done.value, "code", None) != 70
    assert not (tmp_path / "logs").exists()
