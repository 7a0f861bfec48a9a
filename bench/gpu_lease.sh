#!/usr/bin/env bash
# One lease of a lent GPU machine: the benchmark suite, the pass profiles and the GPU tests.
#
#   bash bench/gpu_lease.sh prepare    # here: the release binary and the Vulkan loader
#                                      # (gpu_suite.py --prepare) and the GPU test binaries,
#                                      # stripped, in .gputests/tests.tar.xz (git-ignored)
#   bash bench/gpu_lease.sh run        # there, with carry [".gl", ".gpubench", ".gputests"]
#                                      # and timeout_s 590: suite, tests, profiles into $OUT
#
# The run prints a short table last (the device tool returns the end of the output); the
# suite JSON and log, the profiles' JSON and log and the whole test log come back under
# $OUT (8 files: the device tool returns at most 8). Budget: SUITE_BUDGET
# seconds for the suite (default 200; 0 leaves it out), TEST_SECONDS for each test binary (default 90), and
# no test binary starts after DEADLINE seconds (default 380; the profiles follow, at most
# 60 s each (120 at 6*10^7), none started unless it ends by 585 s: the call's limit is 590;
# PROFILES=0 leaves them out). ONLY="a b" runs those test binaries instead of the list below.
# A binary that runs out of time is diagnosed before it is killed (each thread's state,
# kernel wait channel and CPU ticks, twice a second apart: a deadlock sleeps, a loop
# spins), and the tests it left unfinished are run again alone (HANG_SECONDS each, default
# 30, at most 3, none past the deadline), diagnosed the same way.
set -u
cd "$(dirname "$0")/.."
# every test binary that runs the GPU engine, the most telling first (those after the
# deadline are not run)
TESTS=(gpu_engine sticking ledger mixed_materials friction compare_scenes force_jumps gpu_default_limits
       gpu_grid gpu_pages gpu_rebuild_chain walls periodic stability collide_jkr run_outputs
       contact_network pouring run_no_ledger collide_krijt quiet_batches cli bench library_input
       collide_hysteretic)
# (the working tree, .gl, .gpubench and these must stay under the 64 MiB a call carries;
# `prepare` refuses more than 60. The binaries share most of their code, so one xz archive
# with a dictionary larger than a binary holds them in about a fifth of their gzipped
# sizes. The feature files also run their CPU-only tests there, a few seconds of each
# binary's 90.)

# Runs a command in a session of its own for at most $1 seconds, its output appended to $2
# (emptied first); where it runs out of time, appends the state, wait channel and CPU ticks
# of every thread of every process in the session (twice, a second apart: a deadlock
# sleeps, a loop spins) to $2, then kills the session and returns 124.
watched() {
    local limit=$1 log=$2
    shift 2
    : >"$log"
    local launch=()
    command -v setsid >/dev/null && launch=(setsid)
    # (a background job of a non-interactive shell ignores SIGINT and SIGQUIT, and so
    # would every run the tests signal: restored to the default first)
    ( trap - INT QUIT; exec "${launch[@]}" "$@" ) >>"$log" 2>&1 &
    local pid=$! end=$((SECONDS + limit))
    while kill -0 "$pid" 2>/dev/null && [ "$SECONDS" -lt "$end" ]; do
        sleep 0.2
    done
    if ! kill -0 "$pid" 2>/dev/null; then
        wait "$pid"
        return
    fi
    for sample in 1 2; do
        echo "--- the unfinished session's threads, sample $sample (pid/tid name state wchan utime stime, ticks)"
        # (after the parenthesised name: state, ppid, pgrp, session, ...; utime 12th, stime 13th)
        for proc in $(awk -v sid="$pid" '{ sub(/.*\) /, ""); if ($4 == sid) { split(FILENAME, p, "/"); print p[3] } }' \
                /proc/[0-9]*/stat 2>/dev/null); do
            for task in /proc/"$proc"/task/*; do
                stat=$(sed 's/.*) //' "$task/stat" 2>/dev/null)
                echo "$proc/${task##*/} $(cat "$task/comm" 2>/dev/null) $(cut -d' ' -f1 <<<"$stat")" \
                    "$(cat "$task/wchan" 2>/dev/null) $(cut -d' ' -f12,13 <<<"$stat")"
            done
        done
        [ "$sample" = 1 ] && sleep 1
    done >>"$log"
    kill -9 -- -"$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    return 124
}

case "${1:-}" in
prepare)
    python3 bench/gpu_suite.py --prepare || exit 1
    cargo test --release --no-run --message-format=json 2>/dev/null >/tmp/gpu_lease_tests.json \
        || { echo "cargo test --no-run failed"; exit 1; }
    rm -rf .gputests && mkdir -p .gputests
    for t in "${TESTS[@]}"; do
        exe=$(python3 - "$t" <<'EOF'
import json, sys
for line in open("/tmp/gpu_lease_tests.json"):
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == sys.argv[1] \
            and "test" in m["target"]["kind"] and m.get("executable"):
        print(m["executable"])
EOF
)
        [ -n "$exe" ] || { echo "no test binary for $t"; exit 1; }
        strip -o ".gputests/$t" "$exe" || exit 1
    done
    (cd .gputests && tar cf - "${TESTS[@]}" | xz -9 --lzma2=dict=256MiB -T1 >tests.tar.xz \
        && rm -f "${TESTS[@]}") || { echo "packing the test binaries failed"; exit 1; }
    du -sh .gl .gpubench .gputests
    tree=$(git ls-files -z --cached --others --exclude-standard | du -cb --files0-from=- | tail -n 1 | cut -f1)
    carried=$(( tree + $(du -sb .gl .gpubench .gputests | awk '{s += $1} END {print s}') ))
    echo "carried in all: $(( carried / 1048576 )) MiB"
    [ "$carried" -le $(( 60 * 1048576 )) ] || { echo "over 60 MiB: carry fewer test binaries"; exit 1; }
    ;;
run)
    : "${OUT:?run it on the lent machine, where OUT is set}"
    [ -e /usr/lib/x86_64-linux-gnu/libvulkan.so.1 ] || { for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig; }
    # The test binaries look for the checkout and the powder binary where they were built.
    here=$(pwd)
    [ -e /work/main ] || { mkdir -p /work && ln -s "$here" /work/main; }
    mkdir -p target/release && cp .gpubench/powder target/release/powder
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true
    if [ "${SUITE_BUDGET:-200}" != 0 ]; then
        PYTHONUNBUFFERED=1 python3 bench/gpu_suite.py --out-dir "$OUT" --budget "${SUITE_BUDGET:-200}" \
            >"$OUT/suite.log" 2>&1
        tail -n 25 "$OUT/suite.log"
    fi
    mkdir -p /tmp/gputests
    python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' \
        .gputests/tests.tar.xz /tmp/gputests && chmod +x /tmp/gputests/* \
        || { echo "unpacking the test binaries failed"; exit 1; }
    : >"$OUT/tests.log"
    summary=""
    [ -n "${ONLY:-}" ] && read -r -a TESTS <<<"$ONLY"
    for t in "${TESTS[@]}"; do
        left=$(( ${DEADLINE:-380} - SECONDS ))
        if [ "$left" -lt 20 ]; then summary="$summary$t not run (deadline)"$'\n'; continue; fi
        [ "$left" -gt "${TEST_SECONDS:-90}" ] && left=${TEST_SECONDS:-90}
        start=$(date +%s)
        watched "$left" "/tmp/gputests/$t.log" "/tmp/gputests/$t" --test-threads "${TEST_THREADS:-4}"
        rc=$?
        { echo "=== $t (rc=$rc)"; cat "/tmp/gputests/$t.log"; } >>"$OUT/tests.log"
        line=$(grep "^test result" "/tmp/gputests/$t.log" | tail -n 1)
        summary="$summary$t rc=$rc $(( $(date +%s) - start ))s ${line#test result: }"$'\n'
        if [ "$rc" = 124 ]; then
            # the tests that did not finish, each alone (none past the deadline)
            "/tmp/gputests/$t" --list --format terse 2>/dev/null | sed -n 's/: test$//p' \
                | sort >/tmp/gputests/all.txt
            sed -n 's/^test \(.*\) \.\.\. .*/\1/p' "/tmp/gputests/$t.log" | sort >/tmp/gputests/done.txt
            for name in $(comm -23 /tmp/gputests/all.txt /tmp/gputests/done.txt | head -n 3); do
                if [ $((SECONDS + ${HANG_SECONDS:-30})) -gt "${DEADLINE:-380}" ]; then
                    summary="$summary  $name alone: not run (deadline)"$'\n'
                    continue
                fi
                watched "${HANG_SECONDS:-30}" /tmp/gputests/alone.log "/tmp/gputests/$t" \
                    --exact "$name" --test-threads 1
                rc=$?
                { echo "=== $t $name alone (rc=$rc)"; cat /tmp/gputests/alone.log; } >>"$OUT/tests.log"
                summary="$summary  $name alone rc=$rc"$'\n'
            done
        fi
    done
    # the pass profiles (GPU timestamps): JKR at 10^3 (a step's latency floor: device time
    # against wall time), hysteretic at 6*10^7 (the lists' entries and the particle state in
    # pages beyond the largest buffer), both cases at 10^6, JKR at 10^7
    for run in jkr:1e3:20 hysteretic:6e7:120 hysteretic:1e6:60 jkr:1e6:60 jkr:1e7:60; do
        [ "${PROFILES:-1}" = 0 ] && break
        IFS=: read -r case size limit <<<"$run"
        if [ $((SECONDS + limit)) -gt 585 ]; then echo "profile $case $size: not run (deadline)"; continue; fi
        timeout "$limit" .gpubench/powder bench --backend gpu --case "$case" --sizes "$size" --steps 400 \
            --warmup 32 --profile --json "$OUT/profile_${case}_$size.json" >/tmp/profile.txt 2>&1
        echo "profile $case $size: rc=$?"; grep "passes" /tmp/profile.txt
        cat /tmp/profile.txt >>"$OUT/profiles.log"
    done
    grep -E "^test .* FAILED|^---- |panicked" "$OUT/tests.log" | head -n 30
    printf '%s' "$summary"
    ;;
*)
    echo "usage: bash bench/gpu_lease.sh prepare|run" >&2
    exit 2
    ;;
esac
