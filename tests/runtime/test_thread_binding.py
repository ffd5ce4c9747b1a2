"""Binding Taichi's CPU workers to cores (`tidem.runtime.thread_binding`): the test session's own
ti.init (conftest) binds them when the machine has as many CPUs as workers; TIDEM_BIND's modes."""

import os

import pytest

from tidem.runtime import startup
from tidem.runtime.thread_binding import bind_workers, one_cpu_per_core, process_threads, run_time_ns


@pytest.mark.skipif(len(os.sched_getaffinity(0)) != (os.cpu_count() or 0) or len(os.sched_getaffinity(0)) < 2,
                    reason="binds by default only where the process may use every CPU, two or more")
def test_session_workers_are_bound_one_per_cpu():
    cpus = os.sched_getaffinity(0)
    startup.ensure_taichi("cpu", "float64", len(cpus))  # a start on every CPU (the suite's xdist workers take a share)
    bound = startup.bound_workers
    assert len(bound) == len(cpus)  # as many workers as CPUs
    assert sorted(len(os.sched_getaffinity(t)) for t in bound) == [1] * len(cpus)
    assert set.union(*(os.sched_getaffinity(t) for t in bound)) == cpus  # one on each
    ran: set[int] = set()  # threads that run a parallel loop (others, such as pytest-xdist's, may too)
    for _attempt in range(5):  # a worker that wakes late may find the loop done
        before = {t: run_time_ns(t) for t in process_threads() - {os.getpid()}}
        startup._busy_loop()
        ran |= {t for t in before if run_time_ns(t) > before[t]}
        if bound <= ran:
            break
    assert bound <= ran  # the bound threads are the pool's workers


def test_none_and_too_few_cpus_bind_nothing(monkeypatch):
    calls = []
    monkeypatch.setenv("TIDEM_BIND", "none")
    assert not bind_workers(2, {1}, lambda: calls.append(1))
    monkeypatch.setenv("TIDEM_BIND", "cores")
    assert not bind_workers(len(os.sched_getaffinity(0)) + 1, {1}, lambda: calls.append(1))
    monkeypatch.setenv("TIDEM_BIND", "auto")  # fewer workers than CPUs: left to the scheduler
    if len(os.sched_getaffinity(0)) > 2:
        assert not bind_workers(2, {1}, lambda: calls.append(1))
    assert calls == []


def test_workers_not_told_apart_are_left_alone(monkeypatch):
    monkeypatch.setenv("TIDEM_BIND", "cores")
    idle = set(process_threads()) - {min(process_threads())}  # the loop below runs none of them
    assert not bind_workers(2, idle | {-1}, lambda: None)


def test_first_cpu_of_each_core_first(tmp_path):
    def topology(cores):
        for cpu, core in enumerate(cores):
            top = tmp_path / f"cpu{cpu}" / "topology"
            top.mkdir(parents=True, exist_ok=True)
            (top / "physical_package_id").write_text("0\n")
            (top / "core_id").write_text(f"{core}\n")

    topology([0, 1, 0, 1])  # 2 cores with 2 hyperthreads each, siblings n/2 apart
    assert one_cpu_per_core([0, 1, 2, 3], tmp_path) == [0, 1, 2, 3]
    topology([0, 0, 1, 1])  # siblings side by side
    assert one_cpu_per_core([0, 1, 2, 3], tmp_path) == [0, 2, 1, 3]
    assert one_cpu_per_core([0, 1, 7], tmp_path) == [0, 7, 1]  # no topology for cpu7: a core of its own

