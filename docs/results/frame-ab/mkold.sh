#!/usr/bin/env bash
# frozen copy of vrneural at e90c611 as package vrneural_e90c611 (imports rewritten), in
# /tmp/ab41/old by default, where ab_host_cpu.py and ab_texture_pass.py import it from (or
# set AB_OLD to the folder given here)
set -e
dst=${1:-/tmp/ab41/old}
rm -rf "$dst" && mkdir -p "$dst"
# any clone of this repository holds the commit
root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
git -C "$root" archive e90c611 vrneural | tar -x -C "$dst"
mv "$dst/vrneural" "$dst/vrneural_e90c611"
grep -rl "vrneural" "$dst/vrneural_e90c611" --include=*.py | xargs sed -i -E 's/\bvrneural\.([a-z_])/vrneural_e90c611.\1/g; s/^(\s*)(from|import) vrneural( |$)/\1\2 vrneural_e90c611\3/'
# the bundled packs of that commit (main's own are a newer format the old reader refuses)
sed -i 's/files("vrneural")/files("vrneural_e90c611")/' "$dst/vrneural_e90c611/runtime/scene.py"
