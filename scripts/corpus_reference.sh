#!/usr/bin/env bash
# Every file of a public CAD corpus read by sem and by Open CASCADE (docs/validation.md, 3d):
# face count, each face's area (0.1 %), the model's bounding box; one table row per file.
#
#   scripts/corpus_reference.sh [CORPUS]            the table on stdout
#   scripts/corpus_reference.sh --write-doc [CORPUS] and into docs/validation.md (between the
#                                                   corpus-reference markers)
#
# CORPUS: a folder of .igs/.iges/.stp/.step files, or one holding them in files/ (as the trust
# issue's corpus does); default $SEM_CORPUS, else /work/corpus. The corpus is not part of the
# repository (fetched data is not committed): without it the script says so and exits 0.
# Needs build/occt_check (a build with Open CASCADE; SEM_BUILD names another build folder).
# Exit status 1 when a file that Open CASCADE reads fails the comparison.
set -euo pipefail
cd "$(dirname "$0")/.."

write_doc=0
if [ "${1:-}" = "--write-doc" ]; then
  write_doc=1
  shift
fi
corpus="${1:-${SEM_CORPUS:-/work/corpus}}"
[ -d "$corpus/files" ] && corpus="$corpus/files"
if [ ! -d "$corpus" ]; then
  echo "corpus_reference: no corpus at $corpus: skipped (pass a folder or set SEM_CORPUS)"
  exit 0
fi
checker="${SEM_BUILD:-build}/occt_check"
if [ ! -x "$checker" ]; then
  echo "corpus_reference: $checker not found (build with Open CASCADE first)" >&2
  exit 2
fi
table=$(mktemp)
trap 'rm -f "$table"' EXIT
set +e
OMP_NUM_THREADS=2 "$checker" reference --markdown "$corpus" >"$table"
rc=$?
set -e
cat "$table"
if [ "$write_doc" = 1 ]; then
  doc=docs/validation.md
  grep -q '<!-- corpus-reference:begin -->' "$doc" || { echo "corpus_reference: no markers in $doc" >&2; exit 2; }
  {
    sed -n '1,/<!-- corpus-reference:begin -->/p' "$doc"
    echo "(\`scripts/corpus_reference.sh --write-doc\`, $(date -u +%Y-%m-%d), sem $(git rev-parse --short HEAD))"
    echo
    cat "$table"
    sed -n '/<!-- corpus-reference:end -->/,$p' "$doc"
  } >"$doc.tmp"
  mv "$doc.tmp" "$doc"
  echo "corpus_reference: table written into $doc" >&2
fi
exit $rc
