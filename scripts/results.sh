#!/usr/bin/env bash
# Regenerates docs/results.md by running `epsm compare` on every shipped
# problem (only the epsm binary is used). Usage:
#   scripts/results.sh [EPSM_BINARY] [ITERATIONS] [PROBLEM_NAMES...]
# e.g. scripts/results.sh target/release/epsm 40 caustic mirror layout
set -euo pipefail
epsm=${1:-target/release/epsm}
iterations=${2:-}
shift $(( $# > 2 ? 2 : $# ))
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(caustic mirror layout shadow highlight camera material glass-box)
fi
rows=$(mktemp)
for name in "${names[@]}"; do
  args=(compare "scenes/problems/$name.toml" --methods epsm,drot,l2 --out "out/results/$name" --markdown)
  if [ -n "$iterations" ]; then args+=(--iterations "$iterations"); fi
  "$epsm" "${args[@]}" >> "$rows"
done
{
  echo "# Results"
  echo
  echo "Regenerate with \`scripts/results.sh target/release/epsm\` (runs \`epsm compare\` on each"
  echo "problem in \`scenes/problems/\`; plots and CSVs land in \`out/results/<problem>/\`)."
  echo "Measured on $(nproc) cores, release build, $(date -u +%Y-%m-%d)."
  echo "Parameter error: RMS of θ − θ_true in the parameters' units (scene units, degrees, albedo);"
  echo "image RMSE: linear RGB against the target at the scene resolution."
  echo "What each problem tests, its initial error and notes on its set-up: \`docs/suite.md\`."
  echo "Each run uses its problem's seed (\`optimizer.seed\`, default 1); how much the result varies from seed to seed"
  echo "(caustic, highlight, camera) is also in \`docs/suite.md\`."
  echo
  echo "Seconds per iteration (mean): primal render, gradient-pass trace, matching, solves."
  echo
  echo "| problem | method | parameter error | image RMSE | iterations | wall s | primal s/it | trace s/it | matching s/it | solves s/it |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  cat "$rows"
} > docs/results.md.tmp
mv docs/results.md.tmp docs/results.md
rm -f "$rows"
