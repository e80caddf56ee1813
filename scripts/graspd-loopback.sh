# Sourced by scripts that need a running graspd: `start_graspd [ARGS...]` starts
# target/release/graspd on free loopback ports with ARGS, waits until it listens, sets $addr to
# its gRPC address (host:port) and stops it when the calling script exits.
start_graspd() {
	local root
	root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
	graspd_log="$(mktemp)"
	"$root/target/release/graspd" --grpc-addr 127.0.0.1:0 --rest-addr 127.0.0.1:0 "$@" \
		>"$graspd_log" 2>&1 &
	graspd_pid=$!
	trap 'kill $graspd_pid 2>/dev/null; rm -f "$graspd_log"' EXIT
	for _ in $(seq 100); do
		grep -q "graspd listening" "$graspd_log" && break
		sleep 0.2
	done
	addr="$(sed -n 's/^graspd listening grpc=\([^ ]*\).*/\1/p' "$graspd_log")"
	[ -n "$addr" ] || { cat "$graspd_log"; return 1; }
}
