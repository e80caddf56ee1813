# Sourced by models/*/train.sh: `models_venv DIR` makes sure the training virtualenv
# ($MODELS_VENV, default .tools/models-venv) exists with DIR/requirements.txt installed, and sets
# $py to its python.
models_venv() {
	local root
	root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
	local venv="${MODELS_VENV:-$root/.tools/models-venv}"
	if [ ! -x "$venv/bin/python" ]; then
		python3 -m venv "$venv"
	fi
	"$venv/bin/python" -m pip install --quiet -r "$1/requirements.txt"
	py="$venv/bin/python"
}
