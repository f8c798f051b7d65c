#!/usr/bin/env python3
"""acr against pbrt-v3 and pbrt-v4: whole-process seconds and peak memory on the same scenes.

Each scene renders at its own resolution and spp (pbrt-v3 has no spp flag, so no renderer gets
one), with the same thread count, each run its own process, the renderers' runs alternating
(A B A B ...); the time is wall clock from start to exit and the memory the process's peak
resident set. pbrt-v4 renders the
scene as `pbrt --upgrade` rewrites it (written beside the original, so that relative Include and
PLY paths resolve, and removed afterwards). A renderer whose binary is not given is left out.
pbrt-v4 has no direct-lighting integrator: its upgrade turns pbrt-v3's `directlighting` into
`path` with maxdepth 1, which stops where acr's `directlighting` follows specular chains. On
such a scene acr also renders pbrt-v4's work (`--integrator path`, that maxdepth), and the
speed-up on pbrt-v4 is taken from that run (the row says so); on pbrt-v3 from the scene's own.
The same holds for the light choice: the upgrade turns pbrt-v3's `lightsamplestrategy "spatial"`
into pbrt-v4's light BVH, so acr renders such a scene with `lightsamplestrategy=bvh` for the
comparison with pbrt-v4.

usage: python3 bench/versus.py [--acr PATH] [--pbrt-v3 PATH] [--pbrt-v4 PATH] [--threads N]
           [--runs N] [--spp N] [--scene FILE ...] [--large DIR] [--no-interiors] [--startup]
           [--san-miguel DIR] [--out FILE.md]
With --spp, every renderer reads a copy of the scene (beside it, removed afterwards) whose
Sampler's "integer pixelsamples" is N; the interiors keep the spp of INTERIOR_SPP whatever --spp.
Without --scene: scenes/*.pbrt, the pbrt-v3 scenes in ../shared/scenes/pbrt-v3 when present,
a 1M-triangle mesh written by bench/tools/make_large_scene.py into --large (default
bench/cache/large), and the interiors of bench/scenes/*.pbrt.gz (decompressed beside them for
the renderers that read only text; --no-interiors leaves them out). --san-miguel DIR adds
pbrt-v3-scenes' San Miguel (DIR: its sanmiguel/ folder), as bench/tools/make_san_miguel.py
writes it into bench/cache/san-miguel, at 4 spp. With --startup, each
renderer also renders one pixel of each scene (--pixelbounds 0,1,0,1, pbrt-v3 excepted: it has
no such flag): that whole-process time is its start-up (parse, build, output), and the table
gives it with its share of the full render's time. With --out, the table replaces the text between the markers
<!-- versus:begin --> and <!-- versus:end --> in that file (appended when they are missing).
Python 3 standard library only."""

import argparse
import glob
import gzip
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LONG_RUN = 60.0
BEGIN, END = "<!-- versus:begin -->", "<!-- versus:end -->"
# The interiors render at the spp the benchmarks' history measured them at (a full 1000x676
# frame each), whatever --spp asks of the small scenes.
INTERIOR_SPP = {"conference_room": 8, "theater": 4, "san-miguel": 4}
ONE_PIXEL = "0,1,0,1"
RSS_TAG = "versus-peak-kib "


def gnu_time():
    """GNU time's path when it is installed, else None."""
    path = "/usr/bin/time"
    if not os.access(path, os.X_OK):
        return None
    probe = subprocess.run([path, "-f", f"{RSS_TAG}%M", "true"], capture_output=True, text=True)
    return path if RSS_TAG in probe.stderr else None


def run(cmd):
    """Runs cmd to completion: (seconds, peak RSS in MiB, exit status, stderr tail).
    The peak comes from GNU time, the renderer's parent, where it is installed: a child of
    this script reports at least this script's own peak (Linux carries the parent's
    high-water mark over the exec), which a decompressed interior makes about 100 MiB."""
    launcher = GNU_TIME
    wrapped = [launcher, "-f", f"{RSS_TAG}%M"] + cmd if launcher else cmd
    with tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(wrapped, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        seconds = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode(errors="replace").strip().splitlines()
    # Both in KiB on Linux.
    peak_kib = usage.ru_maxrss
    if launcher and lines and lines[-1].startswith(RSS_TAG):
        peak_kib = int(lines.pop()[len(RSS_TAG):])
    if lines and lines[-1].startswith("Command exited with non-zero status"):
        lines.pop()
    return seconds, peak_kib / 1024.0, proc.returncode, " / ".join(lines[-3:])


def inlined(path, base, depth=0):
    """The text of the scene at `path` with every Include replaced by the included text
    (relative to `base`, the main file's folder, as pbrt-v3 resolves them)."""
    if depth > 16:
        sys.exit(f"versus.py: {path}: Include nested too deeply")
    include = re.compile(r'^[ \t]*Include\s+"([^"]+)"[ \t]*(#[^\n]*)?$', re.MULTILINE)
    text = open(path).read()
    return include.sub(lambda m: inlined(os.path.join(base, m.group(1)), base, depth + 1), text)


def upgraded(pbrt_v4, scene):
    """The scene rewritten by `pbrt --upgrade`, beside the original; None when that fails.
    Included files are inlined first: the upgrader rewrites only the file it is given."""
    flat = os.path.join(os.path.dirname(scene), f".versus-flat-{os.path.basename(scene)}")
    with open(flat, "w") as f:
        f.write(inlined(scene, os.path.dirname(scene)))
    try:
        out = subprocess.run([pbrt_v4, "--upgrade", flat], capture_output=True, text=True)
    finally:
        os.remove(flat)
    if out.returncode != 0:
        print(f"  pbrt-v4 --upgrade failed: {out.stderr.strip()[-300:]}", file=sys.stderr)
        return None
    path = os.path.join(os.path.dirname(scene), f".versus-v4-{os.path.basename(scene)}")
    # pbrt-v4's upgrader keeps pbrt-v3's parameter name, which pbrt-v4's path integrator
    # rejects as unused ("lightsampler" there; its parser.cpp, upgrade of "path").
    text = out.stdout.replace('"string lightsamplestrategy"', '"string lightsampler"')
    with open(path, "w") as f:
        f.write(text)
    return path


def v4_work(original, v4):
    """acr's arguments for the work pbrt-v4 does on the upgraded scene `v4` where the upgrade
    changed it, and their description; None where it did not. The upgrade turns pbrt-v3's
    directlighting into path (with maxdepth 1), and a lightsamplestrategy pbrt-v4 lacks
    ("spatial", pbrt-v3's default) into its own ("bvh")."""
    # Directives at the start of a line: "##Integrator ..." is a comment.
    scene = inlined(original, os.path.dirname(original))
    text = open(v4).read()
    args, what = [], []
    if re.search(r'^\s*Integrator\s+"directlighting"', scene, re.MULTILINE):
        found = re.search(r'^\s*Integrator\s+"path"\s+"integer maxdepth"\s*\[\s*(\d+)',
                          text, re.MULTILINE)
        depth = found.group(1) if found else "5"
        args += ["--integrator", "path", "--set", f"integrator.maxdepth={depth}"]
        what.append(f"path maxdepth {depth}")
    # Outside comments: "##Integrator ... lightsamplestrategy ..." names nothing.
    strategy = re.compile(
        r'^[^#\n]*"string (?:lightsamplestrategy|lightsampler)"\s*\[?\s*"(\w+)"', re.MULTILINE)
    theirs, ours = strategy.search(text), strategy.search(scene)
    if theirs and ours and theirs.group(1) != ours.group(1):
        args += ["--set", f"integrator.lightsamplestrategy={theirs.group(1)}"]
        what.append(f"lightsamplestrategy {theirs.group(1)}")
    return (args, ", ".join(what)) if args else None


def scene_name(path):
    """The scene's name: its file name without `.pbrt` or `.pbrt.gz`."""
    base = os.path.basename(path)
    for suffix in [".pbrt.gz", ".pbrt"]:
        if base.endswith(suffix):
            return base[: -len(suffix)]
    return base


def decompressed(scene):
    """A text copy of a `.pbrt.gz` scene beside it (pbrt-v3 reads only text); None for text."""
    if not scene.endswith(".gz"):
        return None
    path = os.path.join(os.path.dirname(scene), f".versus-text-{scene_name(scene)}.pbrt")
    with gzip.open(scene, "rb") as src, open(path, "wb") as dst:
        shutil.copyfileobj(src, dst)
    return path


def with_spp(scene, spp):
    """A copy of the scene beside it with its Sampler's pixelsamples set to spp; None when the
    scene names none (the renderers' default then applies to all)."""
    text = open(scene).read()
    pattern = re.compile(r'("integer pixelsamples"\s*)\[?\s*\d+\s*\]?')
    if not pattern.search(text):
        return None
    path = os.path.join(os.path.dirname(scene), f".versus-spp-{os.path.basename(scene)}")
    with open(path, "w") as f:
        f.write(pattern.sub(lambda m: f"{m.group(1)}[{spp}]", text))
    return path


def measure_alternating(jobs, runs):
    """Each job's (median seconds, peak MiB) over `runs` rounds, every round running each job
    once in turn (A B C A B C ...) so that a drift of the machine's speed falls on all alike;
    a job of over LONG_RUN seconds runs once. `jobs`: (key, label, cmd). A failed job's result
    is None, after printing why."""
    times = {key: [] for key, _, _ in jobs}
    peaks = {key: [] for key, _, _ in jobs}
    failed = set()
    for _ in range(runs):
        for key, label, cmd in jobs:
            if key in failed or (times[key] and times[key][-1] > LONG_RUN):
                continue
            seconds, peak, code, tail = run(cmd)
            if code != 0:
                print(f"  {label} failed ({code}): {tail}", file=sys.stderr)
                failed.add(key)
                continue
            times[key].append(seconds)
            peaks[key].append(peak)
    results = {}
    for key, label, _ in jobs:
        if key in failed or not times[key]:
            results[key] = None
            continue
        median = statistics.median(times[key])
        print(f"  {label}: {median:.2f} s, {max(peaks[key]):.0f} MiB", file=sys.stderr)
        results[key] = (median, max(peaks[key]))
    return results


def scenes(args):
    if args.scene:
        return [os.path.abspath(s) for s in args.scene]
    found = sorted(glob.glob(os.path.join(ROOT, "scenes", "*.pbrt")))
    shared = os.path.join(ROOT, "..", "shared", "scenes", "pbrt-v3")
    for name in ["killeroo-simple/killeroo-simple", "cornell-box/cornell_box",
                 "spheres-motion/spheres-motion", "veach-mis/mis"]:
        path = os.path.join(shared, f"{name}.pbrt")
        if os.path.exists(path):
            found.append(os.path.normpath(path))
    large = os.path.join(args.large, "large-mesh.pbrt")
    if not os.path.exists(large):
        tool = os.path.join(ROOT, "bench", "tools", "make_large_scene.py")
        subprocess.run([sys.executable, tool, args.large], check=True)
    found.append(os.path.abspath(large))
    if not args.no_interiors:
        found += sorted(glob.glob(os.path.join(ROOT, "bench", "scenes", "*.pbrt.gz")))
    if args.san_miguel:
        out = os.path.join(ROOT, "bench", "cache", "san-miguel")
        tool = os.path.join(ROOT, "bench", "tools", "make_san_miguel.py")
        subprocess.run([sys.executable, tool, args.san_miguel, out], check=True)
        found.append(os.path.join(out, "san-miguel.pbrt"))
    return found


def cell(result):
    if result is None:
        return "failed"
    return f"{result[0]:.2f}" if result[0] >= 1 else f"{result[0]:.3f}"


def startup_cell(start, full):
    """A one-pixel render's seconds and their share of the full render's."""
    if start is None or full is None:
        return "-"
    return f"{cell(start)} ({100 * start[0] / full[0]:.0f}%)"


def table(rows, names, args):
    head = ["scene"] + [f"{n} s" for n in names]
    if "pbrt-v4" in names and "acr" in names:
        head.append("acr speed-up on pbrt-v4")
    if "pbrt-v3" in names and "acr" in names:
        head.append("acr speed-up on pbrt-v3")
    head += [f"{n} peak MiB" for n in names]
    starters = [n for n in names if n != "pbrt-v3"] if args.startup else []
    head += [f"{n} start-up s (share)" for n in starters]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for scene, results in rows:
        work = results.get("acr, pbrt-v4's work")
        label = scene
        if work is not None:
            label += f" (on pbrt-v4: acr {cell(work)} s as {work[2]}, pbrt-v4's upgrade)"
        line = [label] + [cell(results.get(n)) for n in names]
        for other in ["pbrt-v4", "pbrt-v3"]:
            if other in names and "acr" in names:
                acr = results.get("acr")
                if other == "pbrt-v4" and work is not None:
                    acr = work
                theirs = results.get(other)
                ok = acr is not None and theirs is not None
                line.append(f"{theirs[0] / acr[0]:.2f}x" if ok else "-")
        line += ["failed" if results.get(n) is None else f"{results[n][1]:.0f}" for n in names]
        line += [startup_cell(results.get(f"{n} start-up"), results.get(n)) for n in starters]
        lines.append("| " + " | ".join(line) + " |")
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    cpu = platform.processor() or platform.machine()
    spp = f"{args.spp} spp" if args.spp else "its own spp"
    if not args.no_interiors and not args.scene:
        spp += " (the interiors: " + ", ".join(f"{n} {s}" for n, s in INTERIOR_SPP.items()) + ")"
    note = (f"Whole process, {args.threads} threads, median of {args.runs} run(s), "
            f"each scene at its own resolution and {spp}; acr commit {commit}, {os.cpu_count()} "
            f"cores ({cpu}), {time.strftime('%Y-%m-%d')}. Written by `bench/versus.py`.")
    return note + "\n\n" + "\n".join(lines) + "\n"


def write(out, text):
    block = f"{BEGIN}\n{text}{END}"
    old = open(out).read() if os.path.exists(out) else ""
    if BEGIN in old and END in old:
        new = old[: old.index(BEGIN)] + block + old[old.index(END) + len(END):]
    else:
        new = old + ("\n" if old and not old.endswith("\n") else "") + block + "\n"
    with open(out, "w") as f:
        f.write(new)


GNU_TIME = gnu_time()


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--acr", default=os.path.join(ROOT, "target", "release", "acr"))
    p.add_argument("--pbrt-v3")
    p.add_argument("--pbrt-v4")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--runs", type=int, default=1)
    p.add_argument("--spp", type=int)
    p.add_argument("--scene", action="append")
    p.add_argument("--large", default=os.path.join(ROOT, "bench", "cache", "large"))
    p.add_argument("--no-interiors", action="store_true")
    p.add_argument("--san-miguel", metavar="DIR")
    p.add_argument("--startup", action="store_true")
    p.add_argument("--out")
    args = p.parse_args()
    renderers = [("acr", args.acr)]
    renderers += [(n, b) for n, b in [("pbrt-v3", args.pbrt_v3), ("pbrt-v4", args.pbrt_v4)] if b]
    for name, binary in renderers:
        if not os.access(binary, os.X_OK):
            sys.exit(f"versus.py: {name} binary {binary} is not an executable file")
    names = [n for n, _ in renderers]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for original in scenes(args):
            text = decompressed(original)
            spp = INTERIOR_SPP.get(scene_name(original), args.spp)
            scene = with_spp(text or original, spp) if spp else None
            try:
                rows.append(render_all(original, scene or text or original, renderers, args, tmp))
            finally:
                for made in [scene, text]:
                    if made:
                        os.remove(made)
    text = table(rows, names, args)
    print(text)
    if args.out:
        write(args.out, text)


def render_all(original, scene, renderers, args, tmp):
    """One table row: each renderer's (seconds, peak MiB) on `scene`, named after `original`;
    the renderers' runs alternate (`measure_alternating`)."""
    name = scene_name(original)
    if os.sep + "shared" + os.sep in original:
        name = f"{name} (pbrt-v3's)"
    print(name, file=sys.stderr)
    image = os.path.join(tmp, f"{name}.exr")
    threads = str(args.threads)
    jobs, work, v4 = [], None, None
    for label, binary in renderers:
        if label == "acr":
            cmd = [binary, "render", scene, "-o", image, "--threads", threads, "--quiet"]
            jobs.append((label, label, cmd))
            if args.startup:
                one = cmd + ["--pixelbounds", ONE_PIXEL]
                jobs.append((f"{label} start-up", f"{label} one pixel", one))
        elif label == "pbrt-v3":
            cmd = [binary, "--nthreads", threads, "--quiet", "--outfile", image, scene]
            jobs.append((label, label, cmd))
        else:
            v4 = upgraded(binary, scene)
            if v4 is None:
                continue
            cmd = [binary, "--nthreads", threads, "--quiet", "--outfile", image, v4]
            jobs.append((label, label, cmd))
            if args.startup:
                one = cmd[:-1] + ["--pixelbounds", ONE_PIXEL, v4]
                jobs.append((f"{label} start-up", f"{label} one pixel", one))
            work = v4_work(scene, v4)
            acr = dict(renderers).get("acr")
            if work and acr:
                cmd = [acr, "render", scene, "-o", image, "--threads", threads, "--quiet"]
                jobs.append(("acr, pbrt-v4's work", "acr as pbrt-v4's upgrade", cmd + work[0]))
    try:
        results = measure_alternating(jobs, args.runs)
    finally:
        if v4 is not None:
            os.remove(v4)
    if "pbrt-v4" in dict(renderers) and "pbrt-v4" not in results:
        results["pbrt-v4"] = None
    if results.get("acr, pbrt-v4's work") is not None:
        results["acr, pbrt-v4's work"] = (*results["acr, pbrt-v4's work"], work[1])
    return name, results


if __name__ == "__main__":
    main()
