#!/usr/bin/env bash
# Renders one frame over a Slurm cluster: a job array of N tasks, each rendering 1/N of every pixel's
# samples (`fovea render --samples I/N`), then a merge job (`fovea merge`) that depends on the array.
# The merged image equals the single-machine render up to float rounding (docs/cluster.md).
#
#   scripts/slurm/submit.sh --parts N --out DIR [--image NAME.exr] [--fovea BIN] [--tasks LIST] \
#       [--sbatch "OPTIONS"] -- RENDER_ARGS...
#
#   --parts N      the array's size (at most the frame's largest --spp)
#   --out DIR      the folder for the parts, the logs and the image (every node must see it)
#   --image NAME   the merged image in DIR (default image.exr; .png is tone-mapped)
#   --fovea BIN    the fovea binary the nodes run (default: $FOVEA, else `fovea` on PATH); build a
#                  portable one with scripts/slurm/build-portable.sh
#   --tasks LIST   submit only these array tasks (e.g. 2 or 1,3), to complete a split a task died in
#   --after JOBID  with --tasks: the first array's job id, when it may still run; the new merge waits for
#                  both arrays
#   --sbatch OPTS  extra sbatch options for both jobs, e.g. "--partition=cpu --account=lab --time=2:00:00
#                  --cpus-per-task=32" (the SBATCH_* environment variables work too)
# RENDER_ARGS are `fovea render`'s for the whole frame, without --samples and -o.
# Prints the two job ids: "array JOBID" and "merge JOBID".
# The render arguments are checked once (`fovea render --dry-run`, the first task's command line)
# before anything is submitted, so that a typo does not fail every task.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
usage() { sed -n '2,/^# Prints the two job ids/{s/^# \{0,1\}//;p}' "$0"; }
parts="" out="" image=image.exr fovea=${FOVEA:-} tasks="" extra="" after=""
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) usage; exit 0 ;;
    --parts|--out|--image|--fovea|--tasks|--sbatch|--after)
      [ $# -ge 2 ] || { echo "submit.sh: $1 needs a value (see --help)" >&2; exit 2; }
      case $1 in
        --parts) parts=$2 ;;
        --out) out=$2 ;;
        --image) image=$2 ;;
        --fovea) fovea=$2 ;;
        --tasks) tasks=$2 ;;
        --sbatch) extra=$2 ;;
        --after) after=$2 ;;
      esac
      shift 2 ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option '$1' (render options go after --; see --help)" >&2; exit 2 ;;
  esac
done
[[ $parts =~ ^[1-9][0-9]{0,6}$ ]] ||
  { echo "submit.sh: --parts N (a whole number from 1 to 9999999) is required" >&2; exit 2; }
if command -v scontrol >/dev/null; then
  # No controller to ask (scontrol fails): the limit is sbatch's to enforce.
  max_array=$(scontrol show config 2>/dev/null | sed -n 's/^MaxArraySize *= *\([0-9]*\).*/\1/p' || true)
  if [ -n "$max_array" ] && [ "$parts" -gt "$max_array" ]; then
    echo "submit.sh: --parts $parts: this cluster's MaxArraySize is $max_array" >&2; exit 2
  fi
fi
[ $# -gt 0 ] || { echo "submit.sh: give fovea render's arguments after -- (see --help)" >&2; exit 2; }
[ -n "$out" ] || { echo "submit.sh: --out DIR is required" >&2; exit 2; }
[ -n "$fovea" ] || fovea=$(command -v fovea || true)
[ -n "$fovea" ] && [ -x "$fovea" ] ||
  { echo "submit.sh: no fovea binary: give --fovea BIN or set FOVEA (scripts/slurm/build-portable.sh builds one)" >&2; exit 2; }
case $image in
  */*) echo "submit.sh: --image $image: a file name in --out, without a folder" >&2; exit 2 ;;
  *.exr|*.png) ;;
  *) echo "submit.sh: --image $image: the merged image is .exr or .png" >&2; exit 2 ;;
esac
if [ -n "$tasks" ]; then
  for t in ${tasks//,/ }; do
    [[ $t =~ ^[0-9]+$ ]] && [ "$t" -lt "$parts" ] ||
      { echo "submit.sh: --tasks $tasks: each task is a number below --parts $parts" >&2; exit 2; }
  done
fi
[ -z "$after" ] || [[ $after =~ ^[0-9]+$ ]] || { echo "submit.sh: --after JOBID (a job id)" >&2; exit 2; }
[ -z "$after" ] || [ -n "$tasks" ] ||
  { echo "submit.sh: --after waits for an earlier array while --tasks completes it: give --tasks too" >&2; exit 2; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# The sbatch options, split as a shell would (quotes kept together: --comment="two words").
sbatch_extra=()
if [ -n "$extra" ]; then
  printf '%s' "$extra" | xargs printf '%s\0' >"$scratch/sbatch-words" 2>"$scratch/xargs.log" ||
    { echo "submit.sh: --sbatch '$extra': $(head -1 "$scratch/xargs.log") (an unmatched quote?)" >&2; exit 2; }
  while IFS= read -r -d '' word; do sbatch_extra+=("$word"); done <"$scratch/sbatch-words"
fi
fovea=$(cd "$(dirname "$fovea")" && pwd)/$(basename "$fovea")
# The first task's command line, checked before anything is created or submitted.
if ! check=$("$fovea" render "$@" --samples "0/$parts" --dry-run --quiet -o "$scratch/part-0000.fvpart" 2>&1); then
  echo "submit.sh: fovea render refuses these arguments; nothing was submitted:" >&2
  echo "$check" >&2
  exit 2
fi
command -v sbatch >/dev/null || { echo "submit.sh: sbatch not found; run this on a Slurm login node" >&2; exit 2; }
mkdir -p "$out" 2>/dev/null && touch "$out/.submit-check" 2>/dev/null ||
  { echo "submit.sh: --out $out: cannot create files in that folder" >&2; exit 2; }
rm -f "$out/.submit-check"
out=$(cd "$out" && pwd)
# A whole new split into a folder that holds parts would merge them with the new ones.
if [ -z "$tasks" ] && compgen -G "$out/part-*.fvpart" >/dev/null; then
  echo "submit.sh: $out already holds parts (part-*.fvpart); use an empty folder, or --tasks to complete that split" >&2
  exit 2
fi
# The jobs' environment is given explicitly: some sites set SBATCH_EXPORT=NONE.
export_env="--export=ALL,FOVEA=$fovea,FOVEA_PARTS=$parts,FOVEA_OUT=$out,FOVEA_IMAGE=$image"
array=${tasks:-0-$((parts - 1))}
# ${a[@]+"${a[@]}"}: an empty array under `set -u` on bash before 4.4.
array_job=$(sbatch --parsable ${sbatch_extra[@]+"${sbatch_extra[@]}"} "$export_env" --array="$array" \
  --output="$out/part-%a.log" "$here/render-part.sbatch" "$@")
array_job=${array_job%%;*}
merge_job=$(sbatch --parsable ${sbatch_extra[@]+"${sbatch_extra[@]}"} "$export_env" \
  --dependency="afterany:$array_job${after:+:$after}" --output="$out/merge-%j.log" "$here/merge.sbatch")
merge_job=${merge_job%%;*}
echo "array $array_job"
echo "merge $merge_job"
