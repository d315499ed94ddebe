"""How the default build shares its work between threads, counted in instructions (no clock):
each phase's work, serial part and critical path on two threads, and the Amdahl estimate of the
speed-up that follows (instructions on one thread ÷ critical-path instructions on T).

    python bench/build_threads.py [--scenes sponza,room1m,uniform1m] [--threads 2] [--spec bvhlab:]

Builds bench/cpp's bvh_bench with -DBVHLAB_WORK_TRACE=ON (build/bench_trace: callgrind marks at
every pool task, deferred job and build phase, bvhlab/work_trace.h) and runs one build of each
scene under `valgrind --tool=callgrind --separate-threads=yes`, on 1 and on T threads. Every mark
dumps the instructions its thread ran since its last mark. The script rebuilds from them the
calling thread's serial segments, each pool run's tasks and the deferred jobs (a job's parts join
the queue when it ends), then schedules them on T ideal threads as the code does (a run's tasks in
index order, each to the first free thread; jobs largest first, from one queue): the critical path.
Waiting and spinning (the workers' `idle`, the caller's `wait`) count as nothing. What it leaves
out: memory bandwidth, caches, page faults, wake-up latency — the clock's share of the story.

    python bench/build_threads.py --perf [--scenes sponza] [--rounds 4] [--repeat 15] [--against EXE]

The clock's share, in CPU time rather than wall time (which the other users of a shared machine
spoil): the Release bvh_bench (build/bench) runs its builds under `perf record -e cpu-clock`
(sampled on-CPU time of every thread, no hardware counters needed) on 1 and on T threads, the two
alternating for `--rounds` rounds, and the samples are summed per function: CPU milliseconds per
build, 1T beside T, so that what going parallel adds shows by function (the splice, allocation,
waking threads, and the kernels' own slow-down where the threads share caches and memory).
`--against EXE` adds another bvh_bench's columns, interleaved with the first's (before/after).
On a loaded machine a waiting thread's spin yields the core, so spinning is under-counted there.
"""

from __future__ import annotations

import argparse
import heapq
import json
import re
import subprocess
import sys
import tempfile
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build" / "bench_trace"


def build_trace_bench() -> Path:
    """bvh_bench with the work marks compiled in (build/bench_trace, Release)."""
    args = ["cmake", "-S", str(ROOT), "-B", str(BUILD), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release"]
    args += ["-DBVHLAB_TESTS=ON", "-DBVHLAB_VULKAN=OFF", "-DBVHLAB_PYTHON=OFF", "-DBVHLAB_WORK_TRACE=ON"]
    subprocess.run(args + ["-DBVHLAB_TINYBVH_DIR="], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(BUILD), "--target", "bvh_bench"], check=True, stdout=subprocess.DEVNULL)
    return BUILD / "bench" / "cpp" / "bvh_bench"


@dataclass
class Segment:
    """One thread's instructions between two marks, named by the mark that ends it."""

    label: str
    cost: int
    functions: dict[str, int] = field(default_factory=dict)  # self cost by function


_DUMP = re.compile(r"^cg\.\d+(?:\.(\d+))?-(\d+)$")  # cg.PID.DUMP-THREAD, or cg.PID-THREAD at termination


def read_dump(path: Path, names: dict[str, str]) -> Segment:
    """A callgrind dump file: its trigger's name, total Ir and self Ir by function. `names`: the
    compressed function names seen so far (callgrind defines each once per process, in the first
    dump that has it)."""
    label, total, functions = "", 0, defaultdict(int)
    current, skip_next = None, False
    for line in path.read_text().splitlines():
        if line.startswith("desc: Trigger:"):
            trigger = line[len("desc: Trigger:") :].strip()
            label = trigger[len("Client Request:") :].strip() if trigger.startswith("Client Request:") else "end"
        elif line.startswith("summary:") or line.startswith("totals:"):
            total = int(line.split()[1])
        elif line.startswith("fn="):
            m = re.match(r"fn=\((\d+)\)(?: (.*))?", line)
            if m:
                if m.group(2):
                    names[m.group(1)] = m.group(2)
                current = names.get(m.group(1), m.group(1))
            else:
                current = line[3:]
        elif line.startswith("cfn="):  # a callee: may define a name too
            m = re.match(r"cfn=\((\d+)\) (.*)", line)
            if m:
                names[m.group(1)] = m.group(2)
        elif line.startswith("calls="):
            skip_next = True
        elif line and (line[0].isdigit() or line[0] in "+-*"):
            if skip_next:
                skip_next = False
                continue
            parts = line.split()
            if len(parts) >= 2 and current is not None:
                functions[current] += int(parts[1])
    return Segment(label, total, dict(functions))


def read_threads(folder: Path) -> dict[int, list[Segment]]:
    """Each thread's segments in order (thread 1 is the calling thread)."""
    per_thread: dict[int, list[tuple[int, Segment]]] = defaultdict(list)
    files = []
    for path in folder.iterdir():
        m = _DUMP.search(path.name)
        if m:  # the termination dumps come last
            files.append((int(m.group(1)) if m.group(1) else 1 << 40, int(m.group(2)), path))
    names: dict[str, str] = {}
    for dump, thread, path in sorted(files):
        segment = read_dump(path, names)
        if segment.label:  # not the empty file callgrind leaves under the plain name
            per_thread[thread].append((dump, segment))
    return {t: [s for _, s in sorted(v, key=lambda x: x[0])] for t, v in sorted(per_thread.items())}


def list_schedule(costs: list[int], threads: int) -> int:
    """Makespan of tasks handed out in this order, each to the first free of `threads` threads."""
    free = [0] * max(1, threads)
    for c in costs:
        t = heapq.heappop(free)
        heapq.heappush(free, t + c)
    return max(free)


def job_schedule(jobs: list[tuple[int, int, int]], threads: int) -> int:
    """Makespan of build_deferred's queue on `threads` threads: jobs (begin, end, cost); a job whose
    range lies inside another's is queued when that one (the smallest such) ends; the largest
    queued job goes to the first free thread."""
    order = sorted(range(len(jobs)), key=lambda k: (jobs[k][1] - jobs[k][0], -jobs[k][0]))
    parent = [-1] * len(jobs)
    for k in range(len(jobs)):  # the smallest strictly larger range containing it
        b, e, _ = jobs[k]
        best = None
        for j in order:
            bj, ej, _ = jobs[j]
            if j != k and bj <= b and e <= ej and (ej - bj) > (e - b):
                best = j
                break
        parent[k] = -1 if best is None else best
    children = defaultdict(list)
    for k, p in enumerate(parent):
        children[p].append(k)
    queue = [(-(jobs[k][1] - jobs[k][0]), jobs[k][0], k) for k in children[-1]]
    heapq.heapify(queue)
    running: list[tuple[int, int]] = []  # (end time, job)
    now, idle = 0, max(1, threads)
    end = 0
    while queue or running:
        while queue and idle:
            _, _, k = heapq.heappop(queue)
            heapq.heappush(running, (now + jobs[k][2], k))
            idle -= 1
        now, k = heapq.heappop(running)
        idle += 1
        end = max(end, now)
        for c in children[k]:
            heapq.heappush(queue, (-(jobs[c][1] - jobs[c][0]), jobs[c][0], c))
    return end


@dataclass
class Phase:
    work: int = 0  # instructions of every thread but waiting
    serial: int = 0  # the calling thread's, outside pool runs
    path: int = 0  # critical path on the threads
    runs: int = 0
    serial_functions: dict[str, int] = field(default_factory=lambda: defaultdict(int))


def analyse(threads: dict[int, list[Segment]]) -> dict[str, Phase]:
    """Per phase: work, serial part and critical path (see the module's docstring)."""
    caller = min(threads)
    tasks: dict[int, dict[int, int]] = defaultdict(dict)
    jobs: dict[int, list[tuple[int, int, int]]] = defaultdict(list)
    overhead: dict[int, int] = defaultdict(int)  # the deferred queue's taking of jobs
    for segments in threads.values():  # every thread's tasks, jobs and queue time, by run
        pending_jobs, pending_queue = [], 0
        for s in segments:
            w = s.label.split()
            if w[0] == "job":
                pending_jobs.append((int(w[1]), int(w[2]), s.cost))
            elif w[0] == "queue":
                pending_queue += s.cost
            elif w[0] == "task":
                run, i = int(w[1]), int(w[2])
                tasks[run][i] = s.cost
                jobs[run] += pending_jobs
                overhead[run] += pending_queue
                pending_jobs, pending_queue = [], 0
    phases: dict[str, Phase] = defaultdict(Phase)
    phase = "start"
    for s in threads[caller]:
        w = s.label.split()
        if w[0] in ("task", "job", "queue", "wait", "idle"):
            continue  # counted with their run below (waiting counts as nothing)
        p = phases[phase]
        p.work += s.cost
        p.serial += s.cost
        p.path += s.cost
        for fn, c in s.functions.items():
            p.serial_functions[fn] += c
        if w[0] == "phase":
            phase = w[1]
        elif w[0] == "run":
            run, t = int(w[1]), int(w[2])
            p = phases[phase]
            p.runs += 1
            costs = [tasks[run][i] for i in sorted(tasks[run])]
            p.work += sum(costs) + sum(c for *_, c in jobs[run]) + overhead[run]
            if jobs[run]:
                p.path += job_schedule(jobs[run], t) + max(costs)
            else:
                p.path += list_schedule(costs, t)
    return phases


def count(exe: Path, mesh: Path, spec: str, threads: int, folder: Path) -> dict[str, Phase]:
    folder.mkdir(parents=True, exist_ok=True)
    cmd = ["valgrind", "--tool=callgrind", "--separate-threads=yes", "--instr-atstart=no"]
    cmd += [f"--callgrind-out-file={folder}/cg.%p", str(exe), "once", str(mesh), "--peer", spec]
    subprocess.run(cmd + ["--threads", str(threads)], check=True, capture_output=True)
    return analyse(read_threads(folder))


def summary(name: str, one: dict[str, Phase], many: dict[str, Phase], threads: int) -> dict:
    w1 = sum(p.work for p in one.values())
    wt = sum(p.work for p in many.values())
    path = sum(p.path for p in many.values())
    serial = sum(p.serial for p in many.values())
    print(
        f"\n{name}: 1 thread {w1 / 1e6:.1f} M instructions; {threads} threads {wt / 1e6:.1f} M "
        f"({wt / w1 - 1:+.2%}), critical path {path / 1e6:.1f} M, serial {serial / 1e6:.1f} M "
        f"({serial / w1:.2%} of 1T): speed-up estimate {w1 / path:.3f}x"
    )
    print(
        f"  {'phase':10s} {'1T work M':>10s} {'work M':>9s} {'serial M':>9s} {'path M':>9s} "
        f"{'ideal M':>9s} {'runs':>5s}"
    )
    rows = {}
    for ph in sorted(set(one) | set(many), key=lambda k: -many.get(k, Phase()).path):
        a, b = one.get(ph, Phase()), many.get(ph, Phase())
        ideal = b.serial + (b.work - b.serial) / threads
        print(
            f"  {ph:10s} {a.work / 1e6:10.2f} {b.work / 1e6:9.2f} {b.serial / 1e6:9.2f} {b.path / 1e6:9.2f} "
            f"{ideal / 1e6:9.2f} {b.runs:5d}"
        )
        top = sorted(b.serial_functions.items(), key=lambda kv: -kv[1])[:4]
        if b.serial > 0.002 * w1:
            for fn, c in top:
                print(f"      serial {c / 1e6:8.2f} M  {fn[:90]}")
        rows[ph] = {"work_1t": a.work, "work": b.work, "serial": b.serial, "path": b.path, "runs": b.runs}
    return {"work_1t": w1, "work": wt, "path": path, "serial": serial, "speedup_estimate": w1 / path, "phases": rows}


def perf_samples(exe: Path, mesh: Path, spec: str, threads: int, repeat: int, freq: int) -> tuple[dict, int]:
    """cpu-clock samples by function of one bvh_bench run's timed builds, pinned to `threads` cores,
    and how many builds they are."""
    import _peers

    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "perf.data"
        cmd = ["perf", "record", "-q", "-e", "cpu-clock", "-F", str(freq), "-k", "CLOCK_MONOTONIC", "-o", str(data)]
        cmd += ["--"]
        cmd += ["taskset", "-c", _peers.cores(threads), str(exe), "build", str(mesh), "--peer", spec]
        out = subprocess.run(cmd + ["--repeat", str(repeat), "--threads", str(threads)], capture_output=True, text=True)
        if out.returncode:
            raise SystemExit(f"build_threads: {' '.join(cmd)} failed:\n{out.stderr}")
        begin, end = json.loads(out.stdout)["timed"]  # the warm-up's builds (first touches) left out
        report = ["perf", "report", "-i", str(data), "--sort", "sym", "-n", "--stdio", "-q"]
        report += [f"--time={begin:.6f},{end:.6f}"]
        text = subprocess.run(report, capture_output=True, text=True, check=True).stdout
    samples: dict[str, int] = defaultdict(int)
    for line in text.splitlines():
        m = re.match(r"\s*[\d.]+%\s+(\d+)\s+\[.\]\s+(.*)", line)
        if m:  # lambdas by the function they are in; the pool's tasks by what they run
            name = re.sub(
                r"^std::_Function_handler<.*?, (?:bvhlab::)?(?:\(anonymous namespace\)::)?(\w+)[(<].*",
                r"a lambda in \1",
                m.group(2).strip(),
            )
            samples[name] += int(m.group(1))
    return samples, repeat


def perf_compare(exes: list[Path], mesh: Path, spec: str, threads: int, rounds: int, repeat: int) -> dict:
    """CPU ms per build by function, for each (binary, thread count), interleaved over rounds."""
    freq = 10000
    configs = [(k, t) for k in range(len(exes)) for t in (1, threads)]
    totals: list[dict] = [defaultdict(float) for _ in configs]
    for _ in range(rounds):
        for c, (k, t) in enumerate(configs):
            samples, builds = perf_samples(exes[k], mesh, spec, t, repeat, freq)
            for name, n in samples.items():
                totals[c][name] += n * 1e3 / freq / builds / rounds
    labels = [f"{'AB'[k] if len(exes) > 1 else ''}{t}T ms" for k, t in configs]
    names = sorted(set().union(*totals), key=lambda f: -max(abs(x.get(f, 0) - totals[0].get(f, 0)) for x in totals))
    print("  " + " ".join(f"{h:>9s}" for h in labels) + "  function (CPU ms per build, all threads)")
    print("  " + " ".join(f"{sum(x.values()):9.2f}" for x in totals) + "  all")
    for f in names[:24]:
        print("  " + " ".join(f"{x.get(f, 0):9.2f}" for x in totals) + f"  {f[:100]}")
    return {"configs": labels, "exes": [str(e) for e in exes], "ms_per_build": [dict(x) for x in totals]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="sponza,room1m,uniform1m")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--spec", default="bvhlab:", help="bvh_bench peer spec (default: bvhlab's defaults)")
    ap.add_argument("--exe", help="a bvh_bench built with -DBVHLAB_WORK_TRACE=ON (default: build it; --perf: Release)")
    ap.add_argument("--keep", help="folder to keep the dumps in (default: a temporary one)")
    ap.add_argument("--json", help="write the figures to this file")
    ap.add_argument("--perf", action="store_true", help="CPU time by function under perf (see above)")
    ap.add_argument("--rounds", type=int, default=4, help="--perf: rounds of 1T and T runs")
    ap.add_argument("--repeat", type=int, default=15, help="--perf: builds per run")
    ap.add_argument("--against", help="--perf: a second bvh_bench, interleaved with the first")
    args = ap.parse_args()
    import _peers

    results = {}
    if args.perf:
        exes = [Path(args.exe) if args.exe else _peers.build_bvh_bench(None)]
        exes += [Path(args.against)] if args.against else []
        with tempfile.TemporaryDirectory() as tmp:
            for name, tris in _peers.scenes(args.scenes.split(",")).items():
                mesh = Path(tmp) / f"{name}.f32"
                tris.tofile(mesh)
                print(f"\n{name}: {len(tris)} triangles, {args.rounds} rounds of {args.repeat} builds")
                results[name] = perf_compare(exes, mesh, args.spec, args.threads, args.rounds, args.repeat)
        if args.json:
            Path(args.json).write_text(json.dumps(results, indent=1))
        return
    exe = Path(args.exe) if args.exe else build_trace_bench()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(args.keep) if args.keep else Path(tmp)
        for name, tris in _peers.scenes(args.scenes.split(",")).items():
            mesh = Path(tmp) / f"{name}.f32"
            tris.tofile(mesh)
            one = count(exe, mesh, args.spec, 1, base / f"{name}_1")
            many = count(exe, mesh, args.spec, args.threads, base / f"{name}_{args.threads}")
            results[name] = summary(name, one, many, args.threads)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
