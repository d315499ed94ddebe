"""bench/build_threads.py's reading of callgrind's per-thread dumps and its schedules, on dumps
written by hand (the real ones come from a valgrind run: too slow for a test)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import build_threads as bt  # noqa: E402


def dump(folder: Path, name: str, label: str, functions: dict[str, int]) -> None:
    """A dump as callgrind writes it (compressed names, a call line whose cost is not self cost)."""
    lines = ["version: 1", "creator: callgrind", f"desc: Trigger: Client Request: {label}", "events: Ir"]
    for k, (fn, cost) in enumerate(functions.items(), 1):
        lines += [f"fn=({k}) {fn}", f"16 {cost}", f"cfn=({k})", "calls=1 0", "+1 999999"]
    lines += [f"summary: {sum(functions.values())}", f"totals: {sum(functions.values())}"]
    (folder / name).write_text("\n".join(lines) + "\n")


def test_list_schedule_is_greedy_in_order():
    assert bt.list_schedule([5, 3, 3, 3], 2) == 8  # 5 | 3 3, then the last 3 on the first free: 5+3
    assert bt.list_schedule([4, 4, 4], 1) == 12
    assert bt.list_schedule([7], 2) == 7


def test_job_schedule_queues_parts_when_their_job_ends():
    # job [0, 100) (cost 10) splits into [0, 50) and [50, 100) (cost 6 each); [100, 140) is
    # independent (cost 12). Two threads: 10 ‖ 12; the parts start at 10 and 12: end 18.
    jobs = [(0, 100, 10), (0, 50, 6), (50, 100, 6), (100, 140, 12)]
    assert bt.job_schedule(jobs, 2) == 18
    assert bt.job_schedule(jobs, 1) == 34
    assert bt.job_schedule(jobs, 4) == 16  # the parts wait for their job


def test_phases_from_dumps(tmp_path):
    # calling thread 1: 100 serial in "start", then phase top: run 1 (2 threads, 3 tasks of
    # 40/30/30, the caller takes tasks 0 and 2), 20 waiting, 10 serial; thread 2 idles, takes task 1.
    dump(tmp_path, "cg.7.1-01", "phase top", {"setup": 100})
    dump(tmp_path, "cg.7.2-01", "run 1 2 3", {"before": 5})
    dump(tmp_path, "cg.7.3-02", "idle", {"spin": 500})
    dump(tmp_path, "cg.7.4-01", "task 1 0", {"bin": 40})
    dump(tmp_path, "cg.7.5-02", "task 1 1", {"bin": 30})
    dump(tmp_path, "cg.7.6-01", "task 1 2", {"bin": 30})
    dump(tmp_path, "cg.7.7-01", "wait 1", {"spin": 20})
    dump(tmp_path, "cg.7-01", "", {"after": 10})
    (tmp_path / "cg.7-01").write_text((tmp_path / "cg.7-01").read_text().replace("Client Request: ", "Program "))
    threads = bt.read_threads(tmp_path)
    assert [s.label for s in threads[1]] == ["phase top", "run 1 2 3", "task 1 0", "task 1 2", "wait 1", "end"]
    assert threads[1][0].functions == {"setup": 100}  # the call line's cost is not the function's own
    phases = bt.analyse(threads)
    assert (phases["start"].work, phases["start"].path) == (100, 100)
    top = phases["top"]
    assert top.serial == 15 and top.work == 15 + 100 and top.runs == 1
    assert top.path == 15 + 60  # tasks 40 | 30, then 30 on the second thread: 60
