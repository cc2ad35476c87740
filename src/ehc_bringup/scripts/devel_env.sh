# Sourced by the run scripts (experiments.sh, everyday.sh) with their name as $1: strict mode,
# /usr/bin first on PATH (the interpreter with catkin), the repository root as the working
# directory and the devel space sourced (EHC_DEVEL [devel]); exit 2 when it is not built.
set -eo pipefail
export PATH="/usr/bin:/bin:$PATH"
cd "$(dirname "${BASH_SOURCE[0]}")/../../.." || exit 2
EHC_DEVEL="${EHC_DEVEL:-devel}"
[ -f "$EHC_DEVEL/setup.bash" ] || { echo "$1: $EHC_DEVEL/setup.bash not found: build first" >&2; exit 2; }
# shellcheck disable=SC1090,SC1091
source "$EHC_DEVEL/setup.bash"
