#!/usr/bin/env bash
# Makes sure `python3 -c "import MODULE"` works: installs PACKAGE==VERSION from PyPI with pip
# when the module is missing (as the user, or past Debian's externally-managed marker when a
# plain install is refused). The Python clients the tests drive `sfc run` with come this way,
# each pinned to the version its tests were written against, so a new release cannot turn CI
# red on its own. Usage: pip-deps.sh PACKAGE VERSION [MODULE]
set -euo pipefail
package=$1
version=$2
module=${3:-$1}
command -v python3 >/dev/null 2>&1 || { echo "$package-deps: python3 is not installed" >&2; exit 1; }
if python3 -c "import $module" >/dev/null 2>&1; then
    exit 0
fi
echo "$package-deps: installing $package $version with pip" >&2
python3 -m pip install --quiet "$package==$version" >&2 ||
    python3 -m pip install --quiet --user "$package==$version" >&2 ||
    python3 -m pip install --quiet --break-system-packages "$package==$version" >&2
python3 -c "import $module" >/dev/null 2>&1
