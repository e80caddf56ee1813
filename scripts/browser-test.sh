#!/usr/bin/env bash
# The web console's browser test (tests/browser/console.mjs), part of `make test`: installs
# Debian's chromium when it is missing (apt-get; CI runs as root) and playwright-core into
# .tools/browser, starts target/debug/graspd on loopback with a token and the shared 2F-85
# (build it first: `cargo build --bins`), and keeps the screenshot in target/browser/console.png.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -x /usr/bin/chromium ]; then
  echo "installing Debian's chromium for the browser test"
  if ! apt-get install -y -qq chromium >/dev/null 2>&1; then
    apt-get update -qq >/dev/null
    apt-get install -y -qq chromium >/dev/null
  fi
fi
tools="$root/.tools/browser"
if [ ! -d "$tools/node_modules/playwright-core" ]; then
  mkdir -p "$tools"
  npm install --prefix "$tools" --no-audit --no-fund --silent playwright-core@1.64.1
fi
out="$root/target/browser"
mkdir -p "$out"
log="$(mktemp)"
token="browser-test-token"
"$root/target/debug/graspd" --grpc-addr 127.0.0.1:0 --rest-addr 127.0.0.1:0 \
  --auth-token "$token" \
  --import-hand robotiq_2f85="$root/../shared/testdata/hands/robotiq_2f85/2f85.xml" >"$log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null || true; rm -f "$log"' EXIT
for _ in $(seq 150); do grep -q "graspd listening" "$log" && break; sleep 0.2; done
rest="$(sed -n 's/^graspd listening grpc=[^ ]* rest=\([^ ]*\).*/\1/p' "$log")"
[ -n "$rest" ] || { cat "$log"; exit 1; }
BROWSER_TOOLS="$tools" HAND_FOLDER="$root/../shared/testdata/hands/robotiq_2f85" \
  RGB="$root/examples/rgbd/rgb.png" DEPTH="$root/examples/rgbd/depth.png" node "$root/tests/browser/console.mjs" \
  "http://$rest/" "$token" "$out/console.png"
