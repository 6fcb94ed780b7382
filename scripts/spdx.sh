#!/bin/sh
# spdx.sh [--check] [file...]: puts "SPDX-License-Identifier: Apache-2.0" on the first line of
# every source file that lacks it (after a shebang, and after a Python coding line), in the
# comment syntax of the file's language:
#   C (.c, .h)                           /* SPDX-License-Identifier: Apache-2.0 */
#                                        (block comment: the public headers stay valid C89)
#   C++, C# (.cpp, .hpp, .cs)            // SPDX-License-Identifier: Apache-2.0
#   shell, Python, CMake, pkg-config, Doxyfile, TOML, sanitizer lists, .gitignore
#                                        # SPDX-License-Identifier: Apache-2.0
#   Lua (.lua)                           -- SPDX-License-Identifier: Apache-2.0
#   linker version script (.map)         /* SPDX-License-Identifier: Apache-2.0 */
# Without file arguments it walks every file git tracks (run it from anywhere in the clone).
# Left alone: prose and data (Markdown, JSON, Unity .meta/.asmdef, meshes, images, fuzz corpora
# and dictionaries, the ABI baseline), LICENSE and NOTICE, and tests/abi_fixtures/ (headers of
# past releases, kept byte for byte as they were released).
# A file that already names an SPDX licence in its first five lines is left as it is, so the
# script is idempotent. --check changes nothing: it lists the files that lack the line and exits
# 1 if there are any.
set -eu

licence="SPDX-License-Identifier: Apache-2.0"
check=0
if [ "${1:-}" = "--check" ]; then
  check=1
  shift
fi

# The comment line for a path, or nothing when the file is not a source file.
comment_for() {
  case "$1" in
    tests/abi_fixtures/*) return 0 ;;
    *.c | *.h | *.map) printf '/* %s */\n' "$licence" ;;
    *.cpp | *.hpp | *.cs) printf '// %s\n' "$licence" ;;
    *.lua) printf -- '-- %s\n' "$licence" ;;
    *.sh | *.py | *.cmake | *.toml | *.supp | *.pc.in | *.cmake.in | */Doxyfile.in | Doxyfile.in | \
      */CMakeLists.txt | CMakeLists.txt | .gitignore | */.gitignore)
      printf '# %s\n' "$licence" ;;
    *) return 0 ;;
  esac
}

# Number of leading lines the SPDX line goes after: a shebang, then a Python coding line
# (which must stay on line 1 or 2).
header_lines() {
  n=0
  first=$(sed -n 1p "$1")
  case "$first" in '#!'*) n=1 ;; esac
  case "$1" in
    *.py)
      next=$(sed -n "$((n + 1))p" "$1")
      if printf '%s\n' "$next" | grep -Eq '^[ \t\f]*#.*coding[:=][ \t]*[-_.a-zA-Z0-9]+'; then
        n=$((n + 1))
      fi
      ;;
  esac
  echo "$n"
}

if [ "$#" -eq 0 ]; then
  top=$(git rev-parse --show-toplevel)
  cd "$top"
  set -- $(git ls-files)
fi

missing=0
changed=0
for path in "$@"; do
  [ -f "$path" ] || continue
  line=$(comment_for "$path")
  [ -n "$line" ] || continue
  if head -n 5 "$path" | grep -q 'SPDX-License-Identifier:'; then
    continue
  fi
  missing=$((missing + 1))
  if [ "$check" -eq 1 ]; then
    echo "$path"
    continue
  fi
  skip=$(header_lines "$path")
  tmp="$path.spdx.$$"
  {
    if [ "$skip" -gt 0 ]; then head -n "$skip" "$path"; fi
    printf '%s\n' "$line"
    tail -n "+$((skip + 1))" "$path"
  } >"$tmp"
  # Keep the file's mode (executable scripts stay executable).
  chmod "$(stat -c %a "$path")" "$tmp"
  mv "$tmp" "$path"
  changed=$((changed + 1))
done

if [ "$check" -eq 1 ]; then
  if [ "$missing" -gt 0 ]; then
    echo "spdx.sh: $missing file(s) above lack '$licence'"
    exit 1
  fi
  echo "spdx.sh: every source file names its licence"
  exit 0
fi
echo "spdx.sh: added the licence line to $changed file(s)"
