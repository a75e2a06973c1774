#!/usr/bin/env bash
# The full 29-node jump solve as a test of issue 5's targets (status,
# violation, the paper's metric ranges, forward check within 1 cm), the
# same study by Hermite-Simpson, and the shipped studies on the other
# models (status, violation, forward check): about 9 minutes on 2 cores.
# Prints each solve's summary line.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
exec cargo test --release --test integration -- --ignored --nocapture jump_solve::full_jump_meets_the_papers_ranges jump_solve::full_jump_by_hermite_simpson jump_solve::shipped_studies_on_other_models
