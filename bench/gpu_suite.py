#!/usr/bin/env python3
"""The GPU benchmark suite (issue 15): powder on real hardware, in one JSON.

Standard library only. On a machine with a GPU it runs

  * `powder bench --backend gpu` for both packings (hysteretic; JKR with friction and
    rolling) at N = 1e5, 1e6, 1e7 (or as far as the adapter goes: a size the engine refuses
    with "at most M particles fit" is retried once at M rounded down to two digits), each
    size in its own process, without the energy ledger (the step's own cost), then with it
    at 1e6 where time is left;
  * `powder bench --backend both` at N = 1e2, 1e3, 1e4 (both packings, one process): where
    the CPU engine (every core) and the GPU cross over, for `--backend auto`'s choice;
  * the packing example (`examples/packing.toml`, hysteretic with adhesion, periodic in x
    and y) scaled to 1e6 spheres with `--set` (the lattice and the box widened in x and y,
    nothing else changed: no file is edited or copied), `powder run --no-ledger --steps S`,
    and `powder info` of the same scene with and without the ledger;

and writes one JSON, `gpu_suite_<adapter>_<date>.json`: the adapter, driver and limits
(`powder info --json`, plus `nvidia-smi` where present), the machine, the binary, and per
run the particle-steps/s, the GPU bytes per particle, and the estimate of bytes moved per
particle-step (`traffic`: every buffer a pass binds counted once per pass, an upper bound,
see `src/gpu/traffic.rs`) with the bandwidth that rate implies. Timings are measured,
nothing is asserted.

Time: the whole suite keeps inside --budget seconds (540 by default, so a 10-minute call of
a lent machine has a minute to spare): each phase has a deadline (hysteretic by 32 % of the
budget, JKR by 64 %, the packing example by 86 %, the ledger rows by 97 %; the small scenes
first, by 8 %), a size runs only
if its time predicted from the previous size fits before its phase's deadline, each process
is killed at that deadline, and the JSON is rewritten after every run, so whatever ran is
kept even if the suite is stopped.

  python3 bench/gpu_suite.py --quick      # tiny sizes on any adapter (lavapipe here:
                                          # NODEVICE_SELECT=1), JSON into
                                          # /tmp/powder-gpu-suite/; about 15 s (--build:
                                          # cargo build --release first)
  python3 bench/gpu_suite.py              # the full suite, JSON into bench/results/
  python3 bench/gpu_suite.py --prepare    # here, before a lent machine: build, strip the
                                          # binary into .gpubench/, fetch the Vulkan loader
                                          # packages into .gl/ (both git-ignored)

On a lent GPU machine (the device tool's `run`; no Rust there, so the binary built here
travels in .gpubench/, and the Vulkan loader in .gl/), after `--prepare` in the checkout the
session sends:

  carry:   [".gl", ".gpubench"]      timeout_s: 600
  command: for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig;
           PYTHONUNBUFFERED=1 python3 bench/gpu_suite.py --out-dir $OUT

then copy the JSON that comes back into bench/results/ and commit it with the adapter named.
Without a hardware adapter the full suite stops (a lavapipe result is not a GPU result)
unless --allow-software is given; if the NVIDIA Vulkan driver is not found at first, the
suite retries with VK_DRIVER_FILES pointing at /usr/local/nvidia/share/vulkan/icd.d/.
"""

import argparse
import datetime
import hashlib
import json
import math
import os
import platform
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PREPARED = os.path.join(ROOT, ".gpubench")
GL_DIR = os.path.join(ROOT, ".gl")
GL_PACKAGES = ["libvulkan1", "libegl1", "libglvnd0", "libopengl0", "libgl1", "libglx0", "libgles2"]
NVIDIA_ICD = "/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json"
NVIDIA_EGL = "/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json"
PACKING_SCENE = os.path.join(ROOT, "examples", "packing.toml")
SUITE_VERSION = 4

# phase deadlines as fractions of the budget
PHASES = {"small": 0.08, "hysteretic": 0.32, "jkr": 0.64, "packing": 0.86, "ledger": 0.97}

MODES = {
    "full": dict(
        sizes=[100_000, 1_000_000, 10_000_000],
        small_sizes=[100, 1_000, 10_000],
        small_steps=1000,
        ledger_size=1_000_000,
        packing_particles=1_000_000,
        budget=540.0,
        first_steps=256,
        calibrate=True,  # a short run of the smallest size first
        target_seconds=6.0,  # timed stepping per size
        min_steps=64,
        max_steps=4000,
        repeat_below=15.0,  # 3 repeats when a run is predicted under this, s
        packing_fraction=0.5,  # of the packing phase's time left planned for its long run
        packing_ledger_steps=4000,  # the run with the ledger: four chunks
        out_dir=os.path.join(ROOT, "bench", "results"),
    ),
    "quick": dict(
        sizes=[1_000, 4_000],
        small_sizes=[100, 1_000],
        small_steps=50,
        ledger_size=1_000,
        packing_particles=10_000,
        budget=240.0,
        first_steps=16,
        calibrate=False,
        target_seconds=0.5,
        min_steps=8,
        max_steps=64,
        repeat_below=0.0,
        packing_fraction=0.05,
        packing_ledger_steps=128,
        out_dir=os.path.join(tempfile.gettempdir(), "powder-gpu-suite"),
    ),
}


def log(msg):
    print(msg, flush=True)


def utc_now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def slug(text):
    s = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return s[:48] or "unknown"


def git(*args):
    try:
        out = subprocess.run(
            ["git", "-C", ROOT, *args], capture_output=True, text=True, timeout=30
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def git_state():
    head = git("rev-parse", "HEAD")
    if head is None:
        return None
    dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
    return {"commit": head, "dirty": dirty}


def write_json_atomic(path, value):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(value, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


# ---------------------------------------------------------------------------------------
# Preparing a lent-machine run (here)
# ---------------------------------------------------------------------------------------


def target_dir():
    return os.environ.get("CARGO_TARGET_DIR") or os.path.join(ROOT, "target")


def prepare(args):
    """Builds the release binary, strips it into .gpubench/ with a note of what it was built
    from, and fetches the Vulkan loader packages into .gl/."""
    log("building the release binary (cargo build --release) ...")
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    built = os.path.join(target_dir(), "release", "powder")
    os.makedirs(PREPARED, exist_ok=True)
    dest = os.path.join(PREPARED, "powder")
    if shutil.which("strip"):
        subprocess.run(["strip", "-o", dest, built], check=True)
    else:
        shutil.copy2(built, dest)
    os.chmod(dest, 0o755)
    rustc = subprocess.run(["rustc", "-V"], capture_output=True, text=True).stdout.strip()
    build = {
        "built_at": utc_now(),
        "git": git_state(),
        "rustc": rustc or None,
        "host": platform.machine(),
        "binary_bytes": os.path.getsize(dest),
        "binary_sha256": sha256(dest),
        "stripped": bool(shutil.which("strip")),
    }
    write_json_atomic(os.path.join(PREPARED, "build.json"), build)
    log(f"wrote {dest} ({build['binary_bytes'] / 2**20:.1f} MiB) and build.json")
    if build["git"] and build["git"]["dirty"]:
        log("warning: the source tree has uncommitted changes; the results will say so")
    have = [f for f in os.listdir(GL_DIR) if f.endswith(".deb")] if os.path.isdir(GL_DIR) else []
    if have and not args.refetch:
        log(f"{GL_DIR}: {len(have)} packages already there")
    else:
        os.makedirs(GL_DIR, exist_ok=True)
        lists = tempfile.mkdtemp(prefix="apt-amd64-")
        os.makedirs(os.path.join(lists, "partial"), exist_ok=True)
        o = [
            "-oAPT::Architecture=amd64",
            "-oAPT::Architectures=amd64",
            f"-oDir::State::Lists={lists}",
        ]
        log("fetching the Vulkan loader packages (apt-get download) ...")
        subprocess.run(["apt-get", *o, "update"], check=True, stdout=subprocess.DEVNULL)
        subprocess.run(["apt-get", *o, "download", *GL_PACKAGES], cwd=GL_DIR, check=True)
        shutil.rmtree(lists, ignore_errors=True)
    ignored = all(
        subprocess.run(["git", "-C", ROOT, "check-ignore", "-q", path]).returncode == 0
        for path in (".gl/x.deb", ".gpubench/powder")
    )
    size = sum(
        os.path.getsize(os.path.join(d, f))
        for top in (GL_DIR, PREPARED)
        for d, _, files in os.walk(top)
        for f in files
    )
    log(f"carried: {size / 2**20:.1f} MiB (.gl and .gpubench; git-ignored: {ignored})")
    log("now, with the device tool: run(carry=['.gl', '.gpubench'], command='for f in .gl/*.deb; "
        "do dpkg -x $f /; done; ldconfig; PYTHONUNBUFFERED=1 python3 bench/gpu_suite.py "
        "--out-dir $OUT')")


# ---------------------------------------------------------------------------------------
# The environment of a run
# ---------------------------------------------------------------------------------------


def have_vulkan_loader():
    try:
        out = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True).stdout
    except OSError:
        return True  # cannot tell; let wgpu try
    return "libvulkan.so.1" in out


def install_loader(notes):
    """On a bare lent machine (root, no libvulkan), unpacks the carried .gl packages."""
    if have_vulkan_loader():
        return
    debs = sorted(f for f in os.listdir(GL_DIR) if f.endswith(".deb")) if os.path.isdir(GL_DIR) else []
    if not debs or os.geteuid() != 0:
        notes.append("no Vulkan loader found (libvulkan.so.1) and none carried in .gl/")
        return
    for d in debs:
        subprocess.run(["dpkg", "-x", os.path.join(GL_DIR, d), "/"], check=True)
    subprocess.run(["ldconfig"], check=True)
    notes.append(f"unpacked the Vulkan loader from .gl/ ({len(debs)} packages)")


def prepared_is_current():
    """Whether .gpubench/powder was built from the tree as it is (unknown: yes)."""
    try:
        with open(os.path.join(PREPARED, "build.json")) as f:
            built = json.load(f).get("git")
    except (OSError, ValueError):
        return True
    tree = git_state()
    return not (built and tree) or (built == tree and not tree["dirty"])


def find_binary(args):
    """--binary; else .gpubench/powder where there is no cargo (a lent machine) or it was
    built from the tree as it is; else the release build (built first with --build or when
    there is none)."""
    if args.binary:
        found = os.path.abspath(args.binary)
    else:
        prepared = os.path.join(PREPARED, "powder")
        release = os.path.join(target_dir(), "release", "powder")
        cargo = shutil.which("cargo")
        if os.path.exists(prepared) and not args.build and (not cargo or prepared_is_current()):
            found = prepared
        elif cargo and (args.build or not os.path.exists(release)):
            log("building the release binary (cargo build --release) ...")
            subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
            found = release
        elif os.path.exists(release):
            found = release
        else:
            sys.exit("no powder binary: run `python3 bench/gpu_suite.py --prepare` where cargo is")
    if not os.access(found, os.X_OK):
        os.chmod(found, 0o755)  # a copy that lost its mode on the way
    return found


class Runner:
    """Runs powder, with the environment chosen for the adapter."""

    def __init__(self, binary, env):
        self.binary = binary
        self.env = env
        # seconds of a process that opens the adapter and does nothing (powder info)
        self.fixed = 0.0

    def run(self, args, timeout):
        t0 = time.monotonic()
        try:
            p = subprocess.run(
                [self.binary, *args],
                capture_output=True,
                text=True,
                env=self.env,
                timeout=max(1.0, timeout),
                start_new_session=True,
            )
            return p.returncode, p.stdout, p.stderr, time.monotonic() - t0
        except subprocess.TimeoutExpired as e:
            out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
            err = e.stderr.decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
            return None, out, err, time.monotonic() - t0


def detect_adapter(binary, want_hardware, notes):
    """`powder info --json` with the environment that finds the adapter wanted; returns
    (runner, summary)."""
    env = dict(os.environ)
    if want_hardware:
        env.setdefault("POWDER_ADAPTER", "hardware")
    tries = [dict(env)]
    if os.path.exists(NVIDIA_ICD) and "VK_DRIVER_FILES" not in env:
        nv = dict(env, VK_DRIVER_FILES=NVIDIA_ICD)
        if os.path.exists(NVIDIA_EGL):
            nv["__EGL_VENDOR_LIBRARY_FILENAMES"] = NVIDIA_EGL
        tries.append(nv)
    last = ""
    for i, e in enumerate(tries):
        runner = Runner(binary, e)
        rc, out, err, wall = runner.run(["info", "--json"], 120)
        if rc == 0:
            summary = json.loads(out)
            if i > 0:
                notes.append(f"the adapter was found with VK_DRIVER_FILES={NVIDIA_ICD}")
            runner.fixed = wall
            return runner, summary
        last = err.strip()
    return None, last


def nvidia_smi():
    if not shutil.which("nvidia-smi"):
        return None
    q = "name,driver_version,memory.total,clocks.max.sm,clocks.max.mem,pcie.link.gen.current"
    p = None
    for query in (q, "name,driver_version,memory.total"):
        try:
            p = subprocess.run(
                ["nvidia-smi", f"--query-gpu={query}", "--format=csv,noheader"],
                capture_output=True,
                text=True,
                timeout=30,
            )
        except (OSError, subprocess.TimeoutExpired):
            return None
        if p.returncode == 0:
            q = query
            break
    if p is None or p.returncode != 0:
        return None
    keys = q.split(",")
    return [dict(zip(keys, (v.strip() for v in line.split(",")))) for line in p.stdout.splitlines() if line.strip()]


# ---------------------------------------------------------------------------------------
# The runs
# ---------------------------------------------------------------------------------------


def traffic_summary(t, rate):
    """The estimate of a bench row or an info, compacted: per pass bytes per particle."""
    if not t:
        return None
    out = {
        k: t.get(k)
        for k in (
            "step_bytes_per_particle",
            "rebuild_bytes_per_particle",
            "rebuilds_per_step",
            "bytes_per_particle_step",
        )
    }
    n = t.get("_particles")
    out["passes"] = [
        {
            "pass": p["pass"],
            "when": p["when"],
            "bytes_per_particle": p["bytes"] / n if n else None,
            "bound": p["bound"],
        }
        for p in t.get("passes", [])
    ]
    if rate and out.get("bytes_per_particle_step") is not None:
        # GB/s the rate implies if every bound byte moved once per pass
        out["implied_gb_per_s"] = out["bytes_per_particle_step"] * rate / 1e9
    return out


class Suite:
    def __init__(self, args, mode):
        self.args = args
        self.mode = mode
        self.cfg = MODES[mode]
        self.budget = args.budget or self.cfg["budget"]
        self.t0 = time.monotonic()
        self.report = None
        self.path = None

    def elapsed(self):
        return time.monotonic() - self.t0

    def deadline(self, phase):
        return self.budget * PHASES[phase]

    def left(self, phase):
        return self.deadline(phase) - self.elapsed()

    def timeout(self, phase):
        """How long a process of `phase` may run: to its deadline and a little beyond, never
        past the budget."""
        return min(self.left(phase) + 5.0, self.budget - self.elapsed())

    def save(self):
        self.report["elapsed_seconds"] = round(self.elapsed(), 1)
        write_json_atomic(self.path, self.report)

    # -- powder bench, one size per process ------------------------------------------------

    def bench_one(self, case, n, steps, warmup, repeats, ledger, phase, quiet=None, chain=None):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "bench.json")
            cmd = [
                "bench", "--backend", "gpu", "--case", case, "--sizes", str(n),
                "--steps", str(steps), "--warmup", str(warmup), "--repeats", str(repeats),
                "--max-seconds", "1e9", "--json", out,
            ]
            if ledger:
                cmd.append("--ledger")
            if quiet:
                cmd += ["--quiet-batches", quiet]
            if chain:
                cmd += ["--rebuild-chain", chain]
            rc, stdout, stderr, wall = self.runner.run(cmd, self.timeout(phase))
            row = {
                "case": case,
                "particles": n,
"ledger": ledger,
                "quiet_batches_mode": quiet or "auto",
                "rebuild_chain_mode": chain or "on-demand",
                "command": "powder " + " ".join(c if c != out else "FILE" for c in cmd),
                "process_seconds": round(wall, 2),
            }
            if rc is None:
                row.update(status="timeout", note=f"killed at the {phase} phase's deadline after {wall:.0f} s")
                return row, None
            if rc != 0 or not os.path.exists(out):
                row.update(status="failed", note=(stderr.strip().splitlines() or ["?"])[-1])
                return row, None
            with open(out) as f:
                rep = json.load(f)
        r = rep["rows"][0]
        if self.report.get("machine") is None:
            # the machine and version as powder saw them
            self.report["machine"] = rep.get("machine")
            self.report["powder_version"] = rep.get("powder_version")
        rate = r.get("particle_steps_per_second")
        t = r.get("traffic")
        if t:
            t["_particles"] = n
        row.update(
            status=r["status"],
            note=r.get("note"),
            steps=r["steps"],
            warmup=warmup,
            repeats=repeats,
            particle_steps_per_second=rate,
            runs=r.get("runs"),
            seconds_per_step=r.get("seconds_per_step"),
            wall_seconds=r.get("wall_seconds"),
            setup_seconds=r.get("setup_seconds"),
            dt=r.get("dt"),
            gpu_bytes=r.get("gpu_bytes"),
            gpu_bytes_per_particle=r.get("gpu_bytes_per_particle"),
            list_entries=r.get("list_entries"),
            rebuilds=r.get("rebuilds"),
            quiet_batches=r.get("quiet_batches"),
            contacts_per_particle=r.get("contacts_per_particle"),
            traffic=traffic_summary(t, rate),
        )
        return row, rep

    def plan_steps(self, n, per_ps):
        c = self.cfg
        if per_ps is None:
            return c["first_steps"]
        steps = int(c["target_seconds"] / max(per_ps * n, 1e-12))
        return max(c["min_steps"], min(c["max_steps"], steps))

    def predict(self, prev, n, steps, warmup, repeats):
        """Seconds of a process for n particles from the last one: opening the adapter as
        `powder info` took, the rest of what is not stepping (pipelines, the packing, the
        upload, the contact count at the end) scaled with N, conservatively, and the
        stepping at the last rate."""
        if prev is None:
            return 0.0
        m, wall, per_ps, steps0, warmup0, repeats0 = prev
        stepping0 = per_ps * m * (steps0 + warmup0) * repeats0
        fixed = min(self.runner.fixed, wall)
        rest = max(wall - stepping0 - fixed, 0.0)
        return fixed + rest * n / m + per_ps * n * (steps + warmup) * repeats

    def run_case(self, case):
        c = self.cfg
        queue = sorted(self.args.sizes or c["sizes"])
        prev = None  # (n, process s, s per particle-step, steps, warmup, repeats)
        stopped = None  # why the larger sizes are not run
        refused = None  # a size the engine refused: larger ones would be too
        retried = False
        while queue:
            n = queue.pop(0)
            if prev is None and c["calibrate"] and not stopped and refused is None:
                # the smallest size once, briefly: its rate sizes the steps of every size,
                # this one included (a fast GPU does 1e5 particles' steps in well under 1 ms)
                log(f"  {case} N = {n}: calibration, {c['first_steps']} steps")
                row, _ = self.bench_one(case, n, c["first_steps"], 16, 1, False, case)
                row["calibration"] = True
                self.report["calibration"].append(row)
                self.save()
                if row["status"] == "ran":
                    per = row["wall_seconds"] / (n * row["steps"])
                    prev = (n, row["process_seconds"], per, row["steps"], 16, 1)
            per_ps = prev[2] if prev else None
            steps = self.plan_steps(n, per_ps)
            warmup = max(8, min(64, steps // 4))
            one = self.predict(prev, n, steps, warmup, 1)
            repeats = 3 if prev and 3 * one < c["repeat_below"] else 1
            predicted = self.predict(prev, n, steps, warmup, repeats)
            base = {"case": case, "particles": n, "ledger": False}
            if refused is not None and n >= refused:
                row = dict(base, status="skipped", note=f"not run: N = {refused} was refused")
            elif stopped:
                row = dict(base, status="skipped", note=f"not run: {stopped}")
            elif prev and predicted > self.left(case):
                row = dict(
                    base,
                    status="skipped",
                    note=f"predicted {predicted:.0f} s from N = {prev[0]}, "
                    f"{self.left(case):.0f} s left in the {case} phase",
                )
                stopped = f"N = {n} was skipped by the time budget"
            else:
                log(f"  {case} N = {n}: {steps} steps after {warmup}, x{repeats}"
                    + (f" (predicted {predicted:.0f} s)" if prev else ""))
                row, _ = self.bench_one(case, n, steps, warmup, repeats, False, case)
                if row["status"] == "ran":
                    per = row["wall_seconds"] / (n * row["steps"])
                    prev = (n, row["process_seconds"], per, row["steps"], warmup, repeats)
                else:
                    # "... at most M particles fit": once, the largest round count below M
                    fit = re.search(r"at most (\d+) particles fit", row.get("note") or "")
                    m = 0
                    if fit and not retried:
                        retried = True
                        m = int(fit.group(1))
                        digits = 10 ** max(0, len(str(m)) - 2)
                        m = m // digits * digits
                    if m > (prev[0] if prev else 0):
                        refused = n
                        queue = sorted(queue + [m])
                        row["note"] += f" (retried at N = {m})"
                    else:
                        stopped = f"N = {n} {row['status']}"
            log(f"    -> {row['status']}" + (
                f": {row['particle_steps_per_second']:.3e} p-steps/s, "
                f"{row['gpu_bytes_per_particle']:.0f} B/p, "
                f"{row['traffic']['bytes_per_particle_step']:.0f} B/p-step"
                if row["status"] == "ran" else f" ({row.get('note')})"))
            self.report["bench"].append(row)
            self.save()

    def run_ledger(self):
        """Both cases with the energy ledger at the largest size up to the ledger size that
        ran without it and whose time fits what is left (its share: half of it for the first
        case), with the same steps."""
        for k, case in enumerate(("hysteretic", "jkr")):
            ran = sorted(
                (r for r in self.report["bench"]
                 if r["case"] == case and not r["ledger"] and r["status"] == "ran"
                 and r["particles"] <= self.cfg["ledger_size"]),
                key=lambda r: -r["particles"],
            )
            share = self.left("ledger") / (2 - k)
            # the ledger costs about 20 % of the step on a GPU, more on lavapipe: count 2x
            fits = [r for r in ran
                    if 2.0 * r["process_seconds"] / max(r.get("repeats", 1), 1) <= share]
            if not fits:
                if ran:
                    self.report["notes"].append(
                        f"{case} with the ledger not run: {share:.0f} s left, predicted "
                        f"{2.0 * ran[-1]['process_seconds']:.0f} s at N = {ran[-1]['particles']}")
                continue
            base = fits[0]
            n, steps = base["particles"], base["steps"]
            warmup = max(8, min(64, steps // 4))
            log(f"  {case} N = {n} with the ledger: {steps} steps")
            row, _ = self.bench_one(case, n, steps, warmup, 1, True, "ledger")
            self.report["bench"].append(row)
            self.save()

    def run_quiet(self):
        """The hysteretic case at the largest size up to the ledger size that ran, again with
        quiet batches forced (`--quiet-batches always`; `auto` means off on a GPU): what
        skipping the per-step rebuild decision and the empty rebuild dispatches is worth
        there, against the memory their copies cost; and again with the rebuild's passes
        recorded in every step (`--rebuild-chain every-step`, the default before
        2026-11-27): what recording them on demand saves."""
        ran = sorted(
            (r for r in self.report["bench"]
             if r["case"] == "hysteretic" and not r["ledger"] and r["status"] == "ran"
             and r.get("quiet_batches_mode") == "auto"
             and r.get("rebuild_chain_mode", "on-demand") == "on-demand"
             and r["particles"] <= self.cfg["ledger_size"]),
            key=lambda r: -r["particles"],
        )
        fits = [r for r in ran
                if 1.5 * r["process_seconds"] / max(r.get("repeats", 1), 1) <= self.left("ledger")]
        if not fits:
            if ran:
                self.report["notes"].append("quiet batches forced: not run, no time left")
            return
        base = fits[0]
        n, steps = base["particles"], base["steps"]
        warmup = max(8, min(64, steps // 4))
        log(f"  hysteretic N = {n} with quiet batches forced: {steps} steps")
        row, _ = self.bench_one("hysteretic", n, steps, warmup, 1, False, "ledger", quiet="always")
        self.report["bench"].append(row)
        self.save()
        if 1.5 * base["process_seconds"] / max(base.get("repeats", 1), 1) > self.left("ledger"):
            self.report["notes"].append("rebuild chain in every step: not run, no time left")
            return
        log(f"  hysteretic N = {n} with the rebuild's passes in every step: {steps} steps")
        row, _ = self.bench_one("hysteretic", n, steps, warmup, 1, False, "ledger", chain="every-step")
        self.report["bench"].append(row)
        self.save()

    def run_small(self):
        """Both packings at the small sizes on both engines in one process (`--backend
        both`: the CPU engine on every core, then the GPU): a GPU step has a floor of launch
        and read-back latency that the CPU engine undercuts below some N, which these rows
        locate for `--backend auto`."""
        c = self.cfg
        sizes = ",".join(str(n) for n in c["small_sizes"])
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "bench.json")
            cmd = [
                "bench", "--backend", "both", "--case", "both", "--sizes", sizes,
                "--steps", str(c["small_steps"]), "--warmup", str(max(c["small_steps"] // 10, 4)),
                # (a size predicted past a quarter of the phase is left out, so the
                # process ends with its JSON rather than at the deadline without it)
                "--repeats", "3", "--max-seconds", f"{max(self.left('small') / 4, 1.0):.1f}",
                "--json", out,
            ]
            rc, _, stderr, wall = self.runner.run(cmd, self.timeout("small"))
            entry = {
                "command": "powder " + " ".join(x if x != out else "FILE" for x in cmd),
                "process_seconds": round(wall, 2),
            }
            if rc is None or rc != 0 or not os.path.exists(out):
                entry.update(status="timeout" if rc is None else "failed",
                             note=(stderr.strip().splitlines() or ["killed at the phase's deadline"])[-1])
                self.report["small"] = entry
                self.save()
                return
            with open(out) as f:
                rep = json.load(f)
        keep = ("case", "backend", "threads", "particles", "status", "steps",
                "seconds_per_step", "particle_steps_per_second", "contacts_per_particle")
        entry.update(status="ran", rows=[{k: r.get(k) for k in keep} for r in rep["rows"]])
        self.report["small"] = entry
        self.save()

    # -- the packing example -----------------------------------------------------------------

    def packing_sets(self, target):
        """--set overrides widening examples/packing.toml's lattice and box in x and y (the
        periodic axes) to about `target` spheres, everything else unchanged: the lattice's
        sites per axis are floor((max - min - 2r)/spacing) + 1 (scene.rs), the box keeps
        the example's margin of half a gap beyond the lattice."""
        import tomllib  # Python >= 3.11

        with open(PACKING_SCENE, "rb") as f:
            scene = tomllib.load(f)
        block = scene["particles"][0]
        lo, hi = block["min"], block["max"]
        r, s = block["radius"], block["spacing"]
        dom = scene["domain"]["max"]

        def sites(a):
            return math.floor((hi[a] - lo[a] - 2 * r) / s + 1e-9) + 1

        layers = sites(2)
        per_axis = max(1, round(math.sqrt(target / layers)))
        # the region holds per_axis sites with a fifth of a spacing to spare
        width = 2 * r + (per_axis - 1 + 0.2) * s
        margin = [dom[a] - hi[a] for a in range(2)]
        new_hi = [lo[a] + width for a in range(2)]
        new_dom = [new_hi[a] + margin[a] for a in range(2)]
        fmt = lambda v: f"{v:.6g}"
        sets = [
            f"domain.max=[{fmt(new_dom[0])}, {fmt(new_dom[1])}, {fmt(dom[2])}]",
            f"particles[0].max=[{fmt(new_hi[0])}, {fmt(new_hi[1])}, {fmt(hi[2])}]",
        ]
        return sets, per_axis * per_axis * layers, scene["simulation"]

    def run_packing(self):
        target = self.args.packing_particles or self.cfg["packing_particles"]
        sets, expected, sim = self.packing_sets(target)
        set_args = [a for kv in sets for a in ("--set", kv)]
        entry = {
            "scene": "examples/packing.toml",
            "sets": sets,
            "particles_expected": expected,
            "scaled": "the lattice region and the box widened in x and y (the periodic axes) "
            "with --set, nothing else changed; the file is not edited or copied",
            "scene_duration": sim.get("duration"),
        }
        self.report["packing"] = entry
        info = {}
        for ledger in (False, True):
            cmd = ["info", PACKING_SCENE, "--json", *set_args] + ([] if ledger else ["--no-ledger"])
            rc, out, err, wall = self.runner.run(cmd, self.timeout("packing"))
            key = "with_ledger" if ledger else "without_ledger"
            if rc != 0:
                info[key] = {"status": "failed" if rc else "timeout",
                             "note": (err.strip().splitlines() or ["?"])[-1]}
                continue
            v = json.loads(out)
            v["traffic"]["_particles"] = v["particles"]
            info[key] = {
                "particles": v["particles"],
                "step_variant": v["step_variant"],
                "list_entries": v["list_entries"],
                "gpu_bytes": v["total_bytes"],
                "gpu_bytes_per_particle": v["bytes_per_particle"],
                "traffic": traffic_summary(v["traffic"], None),
                "process_seconds": round(wall, 2),
            }
        entry["info"] = info
        entry["runs"] = []
        self.save()
        n = (info.get("without_ledger") or {}).get("particles") or expected
        # a short run first (its rate sizes the long one), then the long one with what is
        # left: half the rate of the short one (contacts form and the lists are rebuilt more
        # often as the lattice lands), a share of the time left for stepping (full: half)
        short = self.cfg["min_steps"] * 4
        self.packing_run(entry, short, set_args, n)
        first = entry["runs"][-1]
        if first["status"] == "ran":
            overhead = max(first["process_seconds"] - first["wall_seconds"], 0.0)
            avail = self.left("packing") - overhead
            share = self.cfg["packing_fraction"]
            steps = int(share * avail * 0.5 * first["particle_steps_per_second"] / n)
            steps = min(steps, 30_000)  # the whole example is 26 083 steps at its dt
            if steps >= 2 * short:
                self.packing_run(entry, steps, set_args, n)
            else:
                entry["runs"].append({"status": "skipped", "steps_planned": steps,
                                      "note": f"{avail:.0f} s left: no longer run"})
            # and a few chunks with the ledger, where the time left allows them (predicted
            # from the short run, the ledger's step counted 1.5 times)
            k = self.cfg["packing_ledger_steps"]
            need = overhead + 1.5 * first["wall_seconds"] * k / short
            if self.left("packing") > 1.5 * need:
                self.packing_run(entry, k, set_args, n, ledger=True)
            else:
                entry["runs"].append({"status": "skipped", "steps_planned": k, "ledger": True,
                                      "note": f"{self.left('packing'):.0f} s left, {need:.0f} s needed"})
        ran = [r for r in entry["runs"] if r["status"] == "ran" and not r.get("ledger")]
        if ran:
            best = max(ran, key=lambda r: r["steps"])
            entry.update({k: v for k, v in best.items() if k != "command"}, status="ran")
        else:
            entry.update(status=first["status"], note=first.get("note"))
        self.save()

    def packing_run(self, entry, steps, set_args, n, ledger=False):
        """`powder run` of the scaled example for `steps` steps from the start (with the
        energy ledger, `powder run`'s default, where `ledger`: its monitor observes every
        chunk, and `stepping_seconds` against `wall_seconds` says what that costs)."""
        if self.left("packing") < 5:
            entry["runs"].append({"status": "skipped", "steps_planned": steps, "ledger": ledger,
                                  "note": "no time left in the packing phase"})
            return
        cmd = ["run", PACKING_SCENE, "--backend", "gpu", "--no-output", "--json",
               "--steps", str(steps), *set_args] + ([] if ledger else ["--no-ledger"])
        log(f"  packing example, {n} spheres: {steps} steps" + (", with the ledger" if ledger else ""))
        rc, out, err, wall = self.runner.run(cmd, self.timeout("packing"))
        run = {
            "command": "powder " + " ".join((f"'{c}'" if " " in c else c) for c in cmd)
            .replace(PACKING_SCENE, "examples/packing.toml"),
            "steps_planned": steps,
            "ledger": ledger,
            "process_seconds": round(wall, 2),
        }
        entry["runs"].append(run)
        if rc != 0:
            run.update(status="failed" if rc else "timeout",
                       note=(err.strip().splitlines() or ["killed at the phase's deadline"])[-1])
            self.save()
            return
        s = json.loads(out)
        rebuilds, done, rate = s.get("rebuilds"), s.get("steps"), s.get("particle_steps_per_second")
        t = (entry["info"].get("with_ledger" if ledger else "without_ledger") or {}).get("traffic")
        est = None
        if t and done:
            # the initial build is counted in rebuilds: the stepping did rebuilds - 1
            per_step = max((rebuilds or 1) - 1, 0) / done
            total = t["step_bytes_per_particle"] + per_step * t["rebuild_bytes_per_particle"]
            est = {
                "step_bytes_per_particle": t["step_bytes_per_particle"],
                "rebuild_bytes_per_particle": t["rebuild_bytes_per_particle"],
                "rebuilds_per_step": per_step,
                "bytes_per_particle_step": total,
                "implied_gb_per_s": total * rate / 1e9 if rate else None,
            }
        run.update(
            status="ran",
            particles=s.get("particles"),
            adapter=s.get("adapter"),
            dt=s.get("dt"),
            steps=done,
            simulated_seconds=s.get("time"),
            wall_seconds=s.get("wall_seconds"),
            # (the rest of the wall time read the state back after each chunk and checked it)
            stepping_seconds=s.get("stepping_seconds"),
            seconds_per_step=s["wall_seconds"] / done if done else None,
            particle_steps_per_second=rate,
            rebuilds=rebuilds,
            quiet_batches=s.get("quiet_batches"),
            outside_domain=s.get("outside_domain"),
            solid_fraction_bounding_box=s.get("solid_fraction_bounding_box"),
            traffic=est,
            note="from the start: the loose lattice falls and begins to settle; without the "
            "energy ledger, no output files",
        )
        self.save()
        if s.get("stepping_seconds") and s.get("wall_seconds"):
            log(f"    -> {s['stepping_seconds']:.2f} of {s['wall_seconds']:.2f} s stepping (the rest: "
                "the state read back and checked after each chunk)")

    # -- the whole suite ----------------------------------------------------------------------

    def run(self):
        args = self.args
        notes = []
        install_loader(notes)
        binary = find_binary(args)
        want_hw = self.mode == "full" and not args.allow_software
        runner, summary = detect_adapter(binary, want_hw, notes)
        if runner is None:
            sys.exit(f"no {'hardware ' if want_hw else ''}GPU adapter: {summary}\n"
                     "(--allow-software runs the full suite on a software adapter)")
        self.runner = runner
        build_json = os.path.join(os.path.dirname(binary), "build.json")
        build = json.load(open(build_json)) if os.path.exists(build_json) else None
        tree = git_state()
        if build and tree and build.get("git") and build["git"]["commit"] != tree["commit"]:
            notes.append(f"the binary was built from {build['git']['commit']}, the tree is at "
                         f"{tree['commit']}: run --prepare again")
        for note in notes:
            log(f"note: {note}")
        date = utc_now()
        os.makedirs(args.out_dir or self.cfg["out_dir"], exist_ok=True)
        name = f"gpu_suite_{slug(summary['name'])}_{date[:10]}"
        if self.mode == "quick":
            name += "_quick"
        out_dir = args.out_dir or self.cfg["out_dir"]
        self.path = os.path.join(out_dir, name + ".json")
        k = 2
        while os.path.exists(self.path):
            self.path = os.path.join(out_dir, f"{name}_{k}.json")
            k += 1
        self.report = {
            "suite": "bench/gpu_suite.py",
            "suite_version": SUITE_VERSION,
            "mode": self.mode,
            "date": date,
            "budget_seconds": self.budget,
            "adapter": {
                k: summary.get(k)
                for k in ("name", "backend", "device_type", "driver", "driver_info", "limits")
            },
            "adapter_features": summary.get("features"),
            "nvidia_smi": nvidia_smi(),
            "host": {
                "hostname": socket.gethostname(),
                "kernel": platform.release(),
                "python": platform.python_version(),
            },
            "machine": None,
            "binary": {
                "path": os.path.relpath(binary, ROOT) if binary.startswith(ROOT) else binary,
                "sha256": sha256(binary),
                "build": build,
            },
            "source_tree": tree,
            "environment": {
                k: runner.env.get(k)
                for k in ("POWDER_ADAPTER", "VK_DRIVER_FILES", "NODEVICE_SELECT")
                if runner.env.get(k)
            },
            "method": {
                "bench": "powder bench --backend gpu, one process per case and size, the dense "
                "lattice packings of src/measure/bench.rs, without the energy ledger unless `ledger`; "
                "the timed steps after warm-up steps, the fastest of `repeats` runs",
                "gpu_bytes_per_particle": "GpuEngine::buffer_bytes() / N: every buffer and "
                "texture the engine allocates",
                "bytes_per_particle_step": "an upper-bound estimate (src/gpu/traffic.rs): per "
                "pass, every distinct buffer or texture it binds counted once, whole; summed "
                "over the passes of every step plus the rebuild's passes times the rebuilds "
                "per timed step, over N; implied_gb_per_s = that times the rate",
                "budget": "phase deadlines " + ", ".join(
                    f"{p} {f:.0%}" for p, f in PHASES.items()) + " of budget_seconds; sizes "
                "predicted past their phase's deadline are skipped",
            },
            "notes": notes,
            "calibration": [],
            "small": None,
            "bench": [],
            "packing": None,
        }
        self.save()
        log(f"adapter: {summary['name']} ({summary['backend']}, {summary['device_type']}, "
            f"{summary['driver']} {summary['driver_info']}); budget {self.budget:.0f} s; "
            f"writing {self.path}")
        log("small scenes, the CPU engine and the GPU:")
        self.run_small()
        for case in ("hysteretic", "jkr"):
            log(f"{case}:")
            self.run_case(case)
        # the machine as powder saw it (from any bench JSON): one more tiny run is not needed
        log("packing example:")
        self.run_packing()
        log("with the energy ledger:")
        self.run_ledger()
        log("with quiet batches forced, and with the rebuild's passes in every step:")
        self.run_quiet()
        if self.report.get("machine") is None:
            self.report["machine"] = machine_info()
        self.save()
        self.small_table()
        self.table()
        log(f"wrote {self.path} ({self.elapsed():.0f} s)")
        return self.path

    def small_table(self):
        small = self.report.get("small") or {}
        if small.get("status") != "ran":
            log(f"small scenes: {small.get('status')} ({small.get('note')})")
            return
        log("small scenes (s a step, CPU on every core / GPU):")
        rows = small["rows"]
        for case in ("hysteretic", "jkr"):
            for n in sorted({r["particles"] for r in rows if r["case"] == case}):
                by = {r["backend"]: r for r in rows if r["case"] == case and r["particles"] == n}
                cpu, gpu = by.get("cpu", {}), by.get("gpu", {})
                a, b = cpu.get("seconds_per_step"), gpu.get("seconds_per_step")
                ratio = f"{a / b:.2f}" if a and b else "-"
                log(f"  {case:<11} {n:>6}: cpu x{cpu.get('threads')} {a if a is None else format(a, '.2e')}"
                    f"  gpu {b if b is None else format(b, '.2e')}  cpu/gpu {ratio}")

    def table(self):
        log("")
        log(f"{'case':<11} {'ledger':<6} {'N':>9} {'status':<8} {'p-steps/s':>10} "
            f"{'s/step':>9} {'GPU B/p':>8} {'B/p-step':>9} {'GB/s est':>9} {'rebuilds':>8}")
        rows = list(self.report["bench"])
        p = self.report.get("packing") or {}
        if p:
            rows.append(dict(
                case="packing", ledger=False, particles=p.get("particles") or p.get("particles_expected"),
                status=p.get("status"), particle_steps_per_second=p.get("particle_steps_per_second"),
                seconds_per_step=p.get("seconds_per_step"),
                gpu_bytes_per_particle=(p.get("info", {}).get("without_ledger") or {}).get("gpu_bytes_per_particle"),
                traffic=p.get("traffic"), rebuilds=p.get("rebuilds"),
            ))
        f = lambda v, spec: "-" if v is None else format(v, spec)
        for r in rows:
            t = r.get("traffic") or {}
            case = r["case"] + ("+quiet" if r.get("quiet_batches_mode") == "always" else "")
            case += "+every" if r.get("rebuild_chain_mode") == "every-step" else ""
            log(f"{case:<11} {('yes' if r.get('ledger') else 'no'):<6} {r['particles']:>9} "
                f"{str(r.get('status')):<8} {f(r.get('particle_steps_per_second'), '.3e'):>10} "
                f"{f(r.get('seconds_per_step'), '.2e'):>9} {f(r.get('gpu_bytes_per_particle'), '.0f'):>8} "
                f"{f(t.get('bytes_per_particle_step'), '.0f'):>9} {f(t.get('implied_gb_per_s'), '.1f'):>9} "
                f"{f(r.get('rebuilds'), 'd'):>8}")


def machine_info():
    info = {"cpu_model": None, "logical_cpus": os.cpu_count(), "memory_total": None}
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                info["cpu_model"] = line.split(":", 1)[1].strip()
                break
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                info["memory_total"] = int(line.split()[1]) * 1024
                break
    except OSError:
        pass
    return info


def parse_sizes(text):
    return [int(float(x)) for x in text.split(",") if x.strip()]


def main():
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="See the module docstring (head -60 bench/gpu_suite.py) and docs/performance.md, "
        "'GPU benchmark suite'.",
    )
    ap.add_argument("--quick", action="store_true", help="tiny sizes on any adapter, to test the suite")
    ap.add_argument("--prepare", action="store_true",
                    help="build and strip the binary into .gpubench/ and fetch the Vulkan loader into .gl/")
    ap.add_argument("--refetch", action="store_true", help="with --prepare: fetch .gl/ again")
    ap.add_argument("--binary", help="the powder binary (default .gpubench/powder, else the release build)")
    ap.add_argument("--build", action="store_true", help="cargo build --release first")
    ap.add_argument("--out-dir", help="where the JSON goes (default bench/results/; --quick: /tmp/powder-gpu-suite/)")
    ap.add_argument("--budget", type=float, help="seconds for the whole suite (default 540; --quick 240)")
    ap.add_argument("--sizes", type=parse_sizes, help="bench sizes, e.g. 1e5,1e6,1e7")
    ap.add_argument("--packing-particles", type=lambda s: int(float(s)),
                    help="the packing example's size (default 1e6; --quick 1e4)")
    ap.add_argument("--allow-software", action="store_true",
                    help="run the full suite on a software adapter too")
    args = ap.parse_args()
    if args.prepare:
        prepare(args)
        return
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    Suite(args, "quick" if args.quick else "full").run()


if __name__ == "__main__":
    main()
