#!/usr/bin/env bash
# frozen copy of vrneural at a commit (default e90c611) as package vrneural_COMMIT (imports
# rewritten), in /tmp/ab41/old by default, where ab_host_cpu.py and ab_texture_pass.py import
# it from (or set AB_OLD to the folder given here); ab_commit.py: `mkold.sh /tmp/ab41/COMMIT
# COMMIT`
set -e
dst=${1:-/tmp/ab41/old}
commit=${2:-e90c611}
pkg=vrneural_$commit
rm -rf "$dst" && mkdir -p "$dst"
# any clone of this repository holds the commit
root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
git -C "$root" archive "$commit" vrneural | tar -x -C "$dst"
mv "$dst/vrneural" "$dst/$pkg"
grep -rl "vrneural" "$dst/$pkg" --include=*.py | xargs sed -i -E "s/\bvrneural\.([a-z_])/$pkg.\1/g; s/^(\s*)(from|import) vrneural( |$)/\1\2 $pkg\3/"
# the bundled packs of that commit (main's own may be a newer format the old reader refuses)
sed -i "s/files(\"vrneural\")/files(\"$pkg\")/" "$dst/$pkg/runtime/scene.py"
