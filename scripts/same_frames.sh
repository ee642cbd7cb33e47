#!/usr/bin/env bash
# Do two builds of sem write the same frames, byte for byte? (issue 33: a restructure changes
# no result.) Every scene of examples/ and every Table 1 model of the shared models (held by
# its first part, under gravity, dropped onto a ground plane) runs a few frames with each
# build; every file a run writes is hashed (the NURBS frames, meshes, USD, glTF, resume
# states), except summary.json, state/run.json and the .semdisc preprocessing file, which hold
# timings and paths, and the IGES global section, which holds the time of writing.
#
#   scripts/same_frames.sh --rev REV        build REV in a scratch worktree (Release), run both
#                                           it and build/sem; exit 1 when any file differs
#   scripts/same_frames.sh --bin A --bin B  two sem binaries already built
#   scripts/same_frames.sh --hashes SEM     just print "case file sha256" lines for one binary
#   --frames N    frames per run (default 3; the paper scenes reach their contacts later,
#                 pass e.g. 40 for them to be part of the check)
#   --only TEXT   the cases whose name contains TEXT
#
# The shared models come from $SEM_SHARED_MODELS (default ../shared/models); without them
# only the examples run. Every run uses --no-cache, OMP_NUM_THREADS=2.
set -euo pipefail
cd "$(dirname "$0")/.."

frames=3
only=""
rev=""
bins=()
hashes_only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --rev) rev="$2"; shift 2 ;;
    --bin) bins+=("$(realpath "$2")"); shift 2 ;;
    --hashes) hashes_only="$(realpath "$2")"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "same_frames.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "$frames" =~ ^[0-9]+$ ]] || { echo "same_frames.sh: --frames needs a whole number" >&2; exit 2; }

root="$(pwd)"
work="$(mktemp -d)"
cleanup() {
  if [ -n "$rev" ] && [ -d "$work/tree" ]; then git -C "$root" worktree remove --force "$work/tree" >/dev/null 2>&1 || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

shared="${SEM_SHARED_MODELS:-$root/../shared/models}"
table1=(beams/beam_cmp3_b.iges castle/castle_super_simple.iges chicken/chicken_simple_closed.iges
        grumpy.iges lamppost.iges mugs/mug_trimmed_complex.iges puft/puft_full_simpler.iges
        rocket/rocket.iges tire.iges)

# The cases: name and scene file.
cases=()
for scene in examples/*.json; do
  cases+=("$(basename "$scene" .json)|$root/$scene")
done
if [ -d "$shared" ]; then
  mkdir -p "$work/scenes"
  for model in "${table1[@]}"; do
    [ -f "$shared/$model" ] || continue
    name="table1_$(basename "$model" .iges)"
    cat >"$work/scenes/$name.json" <<EOF
{
  "objects": [{
    "file": "$shared/$model",
    "material": {"density": 1000, "youngs_modulus": 1e5, "poisson_ratio": 0.45},
    "pin": {"parts": [0]}
  }],
  "gravity": [0, 0, -9.81],
  "integrator": {"type": "linearly_implicit_euler", "dt": 0.01},
  "frames": 3,
  "steps_per_frame": 2,
  "output": {"dir": "out"}
}
EOF
    cases+=("$name|$work/scenes/$name.json")
  done
else
  echo "same_frames.sh: no shared models at $shared: examples only" >&2
fi

# content FILE: the bytes that are the result: an IGES file without its global section (which
# holds the time of writing).
content() {
  case "$1" in
    *.igs) grep -av '^.\{72\}G' "$1" ;;
    *) cat "$1" ;;
  esac
}

# hash_all SEM: "case file sha256" for every case, on stdout.
hash_all() {
  local sem="$1" out="$work/out"
  for c in "${cases[@]}"; do
    local name="${c%%|*}" scene="${c#*|}"
    [ -n "$only" ] && [[ "$name" != *"$only"* ]] && continue
    rm -rf "$out"
    if ! (cd "$(dirname "$scene")" && OMP_NUM_THREADS=2 "$sem" run "$scene" --frames "$frames" \
            --out "$out" --no-cache --quiet >"$work/log" 2>&1); then
      echo "$name (run failed) $(tail -1 "$work/log" | sha256sum | cut -c1-16)"
      continue
    fi
    (cd "$out" && find . -type f ! -name summary.json ! -name '*.semdisc' ! -path ./state/run.json | LC_ALL=C sort |
       while read -r f; do echo "$name ${f#./} $(content "$f" | sha256sum | cut -c1-64)"; done)
  done
  rm -rf "$out"
}

if [ -n "$hashes_only" ]; then
  hash_all "$hashes_only"
  exit 0
fi

if [ -n "$rev" ]; then
  git worktree add --detach "$work/tree" "$rev" >/dev/null 2>&1 ||
    { echo "same_frames.sh: cannot check out $rev" >&2; exit 2; }
  echo "same_frames.sh: building $rev in $work/tree" >&2
  cmake -S "$work/tree" -B "$work/tree/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$work/tree/build" -j"$(nproc)" --target sem_cli >/dev/null 2>&1 ||
    cmake --build "$work/tree/build" -j"$(nproc)" >/dev/null
  bins=("$work/tree/build/sem" "$root/build/sem")
fi
[ ${#bins[@]} -eq 2 ] || { echo "same_frames.sh: give --rev REV, or --bin twice (see --help)" >&2; exit 2; }
for b in "${bins[@]}"; do [ -x "$b" ] || { echo "same_frames.sh: $b is not an executable" >&2; exit 2; }; done

echo "same_frames.sh: ${bins[0]}" >&2
hash_all "${bins[0]}" >"$work/a.txt"
echo "same_frames.sh: ${bins[1]}" >&2
hash_all "${bins[1]}" >"$work/b.txt"
files=$(wc -l <"$work/a.txt")
runs=$(cut -d' ' -f1 "$work/a.txt" | sort -u | wc -l)
if diff "$work/a.txt" "$work/b.txt" >"$work/diff.txt"; then
  echo "same_frames: the same bytes: $files files of $runs runs, $frames frames each"
  exit 0
fi
echo "same_frames: DIFFERENT ($(grep -c '^[<>]' "$work/diff.txt") lines of $files files differ):"
head -40 "$work/diff.txt"
exit 1
