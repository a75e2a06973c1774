#!/usr/bin/env bash
# The paper's two methods on the full 29-node jump, both from the bang-bang
# guess: direct shooting (forward sensitivities) against the collocation
# solve (solved, violation within 1e-3, forward check and the two methods
# within 1 cm): about 4 minutes on 2 cores once built. Prints both solves' summary
# lines.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
exec cargo test --release --test integration -- --ignored --nocapture jump_solve::full_jump_by_shooting
