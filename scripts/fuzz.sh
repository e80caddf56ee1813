#!/usr/bin/env bash
# Runs the cargo-fuzz targets of fuzz/ (docs/fuzzing.md), each for FUZZ_SECONDS (default 600),
# starting from fuzz/seeds/<target> plus the corpus kept in fuzz/corpus/<target>.
# Installs cargo-fuzz into .tools/ on first use. The stable toolchain builds the sanitizer
# runtime through RUSTC_BOOTSTRAP=1 (cargo-fuzz needs -Zsanitizer).
# Usage: scripts/fuzz.sh [TARGET ...]      (no target: all of them, one after the other)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tools="$root/.tools/cargo-fuzz"
if [ ! -x "$tools/bin/cargo-fuzz" ]; then
  cargo install cargo-fuzz --locked --version 0.13.2 --root "$tools"
fi
export PATH="$tools/bin:$PATH" RUSTC_BOOTSTRAP=1
cd "$root/fuzz"
seconds="${FUZZ_SECONDS:-600}"
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(cargo fuzz list)
fi
for t in "${targets[@]}"; do
  mkdir -p "corpus/$t" "artifacts/$t"
  cp -n "seeds/$t"/* "corpus/$t/" 2>/dev/null || true
  echo "== $t: ${seconds} s"
  cargo fuzz run -O "$t" "corpus/$t" -- \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="artifacts/$t/" -print_final_stats=1 2>&1 | tail -n 12
done
