#!/usr/bin/env bash
# Regenerates docs/results.md by running `epsm compare` (methods epsm, drot,
# l2, prdpt) on every shipped problem with seeds 1, 2 and 3 (only the epsm
# binary is used). Usage:
#   [METHODS=epsm,drot] scripts/results.sh [EPSM_BINARY] [ITERATIONS] [PROBLEM_NAMES...]
# e.g. scripts/results.sh target/release/epsm "" caustic mirror layout
# METHODS (comma-separated, default epsm,drot,l2,prdpt) picks the methods run and tabulated.
set -euo pipefail
epsm=${1:-target/release/epsm}
iterations=${2:-}
shift $(( $# > 2 ? 2 : $# ))
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=()
  for f in scenes/problems/*.toml; do names+=("$(basename "$f" .toml)"); done
fi
methods=${METHODS:-epsm,drot,l2,prdpt}
IFS=, read -r -a method_list <<< "$methods"
seeds=(1 2 3)
rows=$(mktemp)
csvs=$(mktemp)
for name in "${names[@]}"; do
  for seed in "${seeds[@]}"; do
    out="out/results/$name-$seed"
    args=(compare "scenes/problems/$name.toml" --methods "$methods" --seed "$seed" --out "$out" --markdown)
    if [ -n "$iterations" ]; then args+=(--iterations "$iterations"); fi
    "$epsm" "${args[@]}" >> "$rows"
    tail -n +2 "$out/compare.csv" >> "$csvs"
  done
done
# compare.csv columns: problem,method,seed,param_error,last_param_error,
# tolerance,solved,image_rmse,iterations,wall_s,...
summary=$(
  for method in "${method_list[@]}"; do
    awk -F, -v m="$method" '$2 == m' "$csvs" > "$csvs.$method"
    runs=$(wc -l < "$csvs.$method")
    solved=$(awk -F, '$7 == "yes"' "$csvs.$method" | wc -l)
    median() { sort -g | awk '{ v[NR] = $1 } END { if (NR == 0) print "n/a"; else if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
    error=$(awk -F, '$4 != "" { print $4 }' "$csvs.$method" | median)
    seconds=$(awk -F, '{ print $10 }' "$csvs.$method" | median)
    echo "| $method | $solved / $runs | $error | $seconds |"
    rm -f "$csvs.$method"
  done
)
per_problem=$(
  for name in "${names[@]}"; do
    line="| $name"
    for method in "${method_list[@]}"; do
      runs=$(awk -F, -v m="$method" -v p="$name" '$1 == p && $2 == m' "$csvs" | wc -l)
      solved=$(awk -F, -v m="$method" -v p="$name" '$1 == p && $2 == m && $7 == "yes"' "$csvs" | wc -l)
      line+=" | $solved/$runs"
    done
    echo "$line |"
  done
)
{
  echo "# Results"
  echo
  echo "Regenerate with \`scripts/results.sh target/release/epsm\` (runs \`epsm compare\` on each"
  echo "problem in \`scenes/problems/\` with seeds 1, 2 and 3; plots and CSVs land in"
  echo "\`out/results/<problem>-<seed>/\`). Measured on $(nproc) cores, release build, $(date -u +%Y-%m-%d)."
  echo "Every problem runs with its automatic settings (\`docs/problem-format.md\`, \"Automatic choices\")."
  echo "Parameter error: RMS of θ − θ_true in the parameters' units (scene units, degrees, albedo), of"
  echo "the best θ (judged on an independent render) and of the last; solved: the best θ's error is at"
  echo "most the problem's \`tolerance\`. Image RMSE: linear RGB of the final (best θ) render against"
  echo "the target at the scene resolution. What each problem tests: \`docs/suite.md\`."
  echo
  echo "## Per method"
  echo
  echo "| method | solved | median parameter error | median wall s |"
  echo "|---|---|---|---|"
  echo "$summary"
  echo
  echo "## Per problem (runs solved of 3)"
  echo
  echo "| problem | ${methods//,/ | } |"
  echo "|---|$(printf -- '---|%.0s' "${method_list[@]}")"
  echo "$per_problem"
  echo
  echo "## Per run"
  echo
  echo "Seconds per iteration (mean): primal render, gradient-pass trace, matching, solves."
  echo
  echo "| problem | method | seed | parameter error (best θ) | last θ | tolerance | solved | image RMSE | iterations | wall s | primal s/it | trace s/it | matching s/it | solves s/it |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  cat "$rows"
} > docs/results.md.tmp
mv docs/results.md.tmp docs/results.md
rm -f "$rows" "$csvs"
