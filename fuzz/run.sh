#!/usr/bin/env bash
# Runs each fuzz target in turn for SECONDS seconds (default 600), at the lowest CPU priority,
# starting from the committed corpus (fuzz/corpus/<target>, read only) and growing a working
# corpus in fuzz/corpus-work/<target> (not committed). Crashes land in fuzz/artifacts/<target>;
# copy each, once fixed, to fuzz/regressions/<target>/ so `cargo test -p thm-scenarios --test
# fuzz_corpus` keeps it fixed. Needs the nightly toolchain and `cargo install cargo-fuzz`.
#
#   fuzz/run.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-600}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(scenario packing_csv checkpoint eos_csv mesher eos_state)
fi
# Release with debug assertions; no sanitizer (the code has no `unsafe`), so more executions.
# FUZZ_TARGET_DIR puts the build elsewhere (default fuzz/target).
flags=(--release --debug-assertions --sanitizer none)
if [ -n "${FUZZ_TARGET_DIR:-}" ]; then
    flags+=(--target-dir "$FUZZ_TARGET_DIR")
fi
cargo +nightly fuzz build "${flags[@]}"
for t in "${targets[@]}"; do
    mkdir -p "corpus-work/$t" "artifacts/$t"
    echo "== $t: ${seconds} s"
    nice -n 19 cargo +nightly fuzz run "${flags[@]}" "$t" "corpus-work/$t" "corpus/$t" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -max_len=65536 \
        -artifact_prefix="artifacts/$t/" -print_final_stats=1 2>&1 | tee "artifacts/$t.log" |
        grep -E '^#[0-9]+ +(INITED|DONE|NEW)|^stat::|^==|panicked|SUMMARY|Test unit written' || true
done
