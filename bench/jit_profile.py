#!/usr/bin/env python3
"""Where the time goes inside lavapipe's JIT-compiled kernels (Linux, perf, objdump).

lavapipe compiles each compute pipeline to machine code in anonymous executable memory,
which `perf report` can only show as addresses. This script runs a powder command, samples
it with `perf record -p PID` while it runs, reads the executable anonymous mappings that
hold samples from /proc/PID/mem (before the process exits), disassembles them with
`objdump -b binary`, and prints per mapping (one kernel each, as a rule) its share of the
samples and the hottest stretches of code, with the memory instructions in them. A
storage-buffer access shows up as its loop over the 8 SIMD lanes: a lane mask test, the
bounds check against the binding's size in the JIT context (`0x7f..(%r12)`), a masked
`vpbroadcastd` load or a `mov` store; a storage-texture load as `vmovdqa` + `vinserti128`
pairs (a gather).

    python3 bench/jit_profile.py -- target/release/powder run SCENE --backend gpu \\
        --no-output --no-ledger --set simulation.duration=10

Options: --wait S (start sampling after S seconds, default 8: past pipeline compilation),
--seconds S (sample for S seconds, default 8), --windows N (hot stretches per mapping,
default 8), --width N (instructions per stretch, default 30), --keep DIR (keep the dumps and
disassemblies). Needs root or perf_event_paranoid <= 1, and the command to run longer than
--wait + --seconds. Run as root on a machine where `NODEVICE_SELECT=1` is set if the Vulkan
device-select layer gets in the way. Standard library only.
"""

import argparse
import collections
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time


def executable_mappings(pid):
    """(start, end) of the anonymous executable mappings of a process."""
    out = []
    with open(f"/proc/{pid}/maps") as f:
        for line in f:
            parts = line.split()
            if len(parts) == 5 and parts[1] == "r-xp":
                a, b = (int(x, 16) for x in parts[0].split("-"))
                out.append((a, b))
    return out


def disassemble(path, start):
    """[(address, text)] of a raw code dump loaded at `start`."""
    r = subprocess.run(
        ["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", f"--adjust-vma={hex(start)}", path],
        capture_output=True, text=True, check=True)
    ins = []
    for line in r.stdout.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+((?:[0-9a-f]{2} )+)\s*(.*)", line)
        if m:
            ins.append((int(m.group(1), 16), m.group(3)))
    return ins


MEMORY = re.compile(r"0x7f[0-9a-f]{2}\(%r1[0-9]\)|\(%r[a-z0-9]+(,%r[a-z0-9]+,\d)?\),%[yx]mm|mov +%e[a-z]+,\(")


def hot_windows(ins, counts, n, width):
    total = sum(counts.get(a, 0) for a, _ in ins) or 1
    sums = sorted(((sum(counts.get(a, 0) for a, _ in ins[i:i + width]), i) for i in range(len(ins))),
                  reverse=True)
    chosen = []
    for s, i in sums:
        if s == 0 or len(chosen) >= n:
            break
        if all(abs(i - j) >= width for j in chosen):
            chosen.append(i)
    for i in sorted(chosen):
        s = sum(counts.get(a, 0) for a, _ in ins[i:i + width])
        mem = " | ".join(t for _, t in ins[i:i + width] if MEMORY.search(t))
        print(f"    {ins[i][0]:x} {100 * s / total:5.1f} %  {mem[:240]}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--wait", type=float, default=8.0)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--windows", type=int, default=8)
    ap.add_argument("--width", type=int, default=30)
    ap.add_argument("--keep")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    cmd = a.command[1:] if a.command[:1] == ["--"] else a.command
    if not cmd:
        ap.error("give the command to profile after --")
    for tool in ("perf", "objdump"):
        if shutil.which(tool) is None:
            sys.exit(f"{tool} not found (apt-get install -y linux-perf binutils)")
    work = a.keep or tempfile.mkdtemp(prefix="jit_profile_")
    os.makedirs(work, exist_ok=True)
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(a.wait)
        if proc.poll() is not None:
            sys.exit("the command ended before sampling started: make it run longer than --wait + --seconds")
        data = os.path.join(work, "perf.data")
        subprocess.run(["perf", "record", "-e", "cpu-clock", "-F", "4000", "-p", str(proc.pid),
                        "-o", data, "--", "sleep", str(a.seconds)],
                       capture_output=True, check=True)
        if proc.poll() is not None:
            sys.exit("the command ended while sampling: make it run longer than --wait + --seconds")
        ips = subprocess.run(["perf", "script", "-i", data, "-F", "ip"], capture_output=True,
                             text=True, check=True).stdout
        counts = collections.Counter(int(x, 16) for x in ips.split())
        total = sum(counts.values()) or 1
        regions = []
        with open(f"/proc/{proc.pid}/mem", "rb") as mem:
            for start, end in executable_mappings(proc.pid):
                n = sum(v for x, v in counts.items() if start <= x < end)
                if n > 0.02 * total:
                    mem.seek(start)
                    path = os.path.join(work, f"jit_{start:x}.bin")
                    with open(path, "wb") as f:
                        f.write(mem.read(end - start))
                    regions.append((n, start, end, path))
    finally:
        proc.kill()
        proc.wait()
    print(f"{total} samples; JIT mappings with more than 2 %: "
          f"{100 * sum(r[0] for r in regions) / total:.1f} % in all")
    for n, start, end, path in sorted(regions, reverse=True):
        print(f"  mapping {start:x}-{end:x}: {100 * n / total:.1f} % of all samples")
        hot_windows(disassemble(path, start), counts, a.windows, a.width)
    if not a.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
