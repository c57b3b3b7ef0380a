# SPDX-License-Identifier: GPL-3.0-or-later
# Sourced: sets PY311 and PY313, the CPythons whose ABIs Blender ships (3.11: Blender 4.2 LTS
# to 5.0; 3.13: Blender 5.1 and later), unless already set. Each is the first found of: the
# newest pyenv build of that version, pythonX.Y on PATH, /usr/bin/pythonX.Y (Debian 12's
# python3 is 3.11). Debian 12 has no Python 3.13 package: without one, the scripts that need
# it stop and say so (set PY313, or build it with pyenv: `pyenv install 3.13`).
find_python() {  # find_python 3.13 -> a path, or nothing
  local version=$1 root candidate
  root=$(pyenv root 2>/dev/null || echo "$HOME/.pyenv")
  for candidate in $(ls -d "$root"/versions/"$version".* 2>/dev/null | sort -V -r); do
    if [ -x "$candidate/bin/python$version" ]; then
      echo "$candidate/bin/python$version"
      return
    fi
  done
  for candidate in "$(command -v "python$version" 2>/dev/null)" "/usr/bin/python$version"; do
    # pyenv's shim answers for every version name; ask the interpreter which it is.
    if [ -n "$candidate" ] && [ -x "$candidate" ] &&
       "$candidate" -c "import sys; sys.exit(sys.version_info[:2] != tuple(map(int, '$version'.split('.'))))" 2>/dev/null; then
      echo "$candidate"
      return
    fi
  done
}

need_python() {  # need_python VARIABLE VERSION WHAT-FOR
  if [ -z "${!1:-}" ] || [ ! -x "${!1}" ]; then
    echo "error: no Python $2 found (needed for $3): set $1=/path/to/python$2; Debian 12" \
         "ships 3.11 only, pyenv can build others (pyenv install $2)" >&2
    exit 1
  fi
}

PY311=${PY311:-$(find_python 3.11)}
PY313=${PY313:-$(find_python 3.13)}
