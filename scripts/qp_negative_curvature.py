#!/usr/bin/env python3
"""Where a dumped SQP subproblem of the jump is nonconvex.

Reads a QP that the SQP wrote as clarabel JSON (`leap solve --dump-qps`,
`examples/sqp_jump_dump`, or `qp_dump_every` in the library), projects its Hessian P onto the null space
of the equality rows (the linearised defects and the other equality
constraints) and reports the reduced Hessian's negative eigenvalues: how
many, their sum, the most negative ones with the variables that carry
them, and the share of the negative curvature per kind of variable.
This is the curvature that the interior-point solver's inertia
correction (`--hessian exact-inertia-corrected`) has to cover with
tau*I, damping every other direction with it.

The variables are named by the jump's layout: per node 1..N the state
(q, qdot, fibre lengths lm, activations a) and then the excitations u,
with t_f last. They are the SQP's variables, scaled by their bounds.

Needs numpy and scipy (not part of leap's install):
    python3 -m venv .venv && .venv/bin/pip install numpy scipy
    leap solve --hessian exact-inertia-corrected --dump-qps \
        --max-iterations 6 --no-forward-check --out /tmp/r
    .venv/bin/python scripts/qp_negative_curvature.py /tmp/r/qps/qp_iter5_qp.json
"""

import argparse
import json
import sys

try:
    import numpy as np
    import scipy.linalg as la
    import scipy.sparse as sp
except ImportError as e:
    sys.exit(f"qp_negative_curvature.py needs numpy and scipy ({e})")


def csc(d, name, path):
    try:
        return sp.csc_matrix(
            (d["nzval"], d["rowval"], d["colptr"]), shape=(d["m"], d["n"])
        )
    except (KeyError, TypeError, ValueError) as e:
        sys.exit(f"{path}: field {name}: not a CSC matrix ({e})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("qp", help="a QP as clarabel JSON")
    ap.add_argument("--nq", type=int, default=7, help="coordinates (7)")
    ap.add_argument("--nm", type=int, default=24, help="muscles (24)")
    ap.add_argument("--top", type=int, default=3, help="eigenvalues to list")
    args = ap.parse_args()
    try:
        with open(args.qp) as f:
            j = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"{args.qp}: {e}")
    P = csc(j.get("P", {}), "P", args.qp).toarray()
    P = np.triu(P)
    P = P + P.T - np.diag(np.diag(P))
    A = csc(j.get("A", {}), "A", args.qp)
    try:
        neq = int(j["cones"][0]["ZeroConeT"])
    except (KeyError, IndexError, TypeError, ValueError):
        sys.exit(f"{args.qp}: field cones[0].ZeroConeT: missing (no equality rows?)")
    n = P.shape[0]
    names = (
        [f"q{i}" for i in range(args.nq)]
        + [f"qd{i}" for i in range(args.nq)]
        + [f"lm{i}" for i in range(args.nm)]
        + [f"a{i}" for i in range(args.nm)]
        + [f"u{i}" for i in range(args.nm)]
    )
    nv = len(names)
    if (n - 1) % nv != 0:
        sys.exit(
            f"{args.qp}: {n} variables are not N nodes of {nv} plus t_f "
            "(an elastic QP, or another model: set --nq and --nm)"
        )

    def name(i):
        if i == n - 1:
            return "tf"
        return f"{names[i % nv]}@{i // nv + 1}"

    def kind(i):
        return "tf" if i == n - 1 else names[i % nv].rstrip("0123456789")

    Z = la.null_space(A[:neq].toarray())
    H = Z.T @ P @ Z
    w, V = la.eigh(H)
    neg = w < 0
    print(f"{args.qp}: {n} variables, {neq} equality rows, null space {Z.shape[1]}")
    print(
        f"reduced Hessian: {neg.sum()} of {len(w)} eigenvalues negative, "
        f"sum {w[neg].sum():.4g}; range [{w[0]:.4g}, {w[-1]:.4g}]"
    )
    for k in range(min(args.top, int(neg.sum()))):
        v = Z @ V[:, k]
        idx = np.argsort(-np.abs(v))[:8]
        print(
            f"  {w[k]:.4g}: "
            + ", ".join(f"{name(i)} {v[i]:+.2f}" for i in idx)
        )
    if neg.any():
        share = ((Z @ V[:, neg]) ** 2 * -w[neg]).sum(axis=1)
        by_kind = {}
        for i in range(n):
            by_kind[kind(i)] = by_kind.get(kind(i), 0.0) + share[i]
        total = sum(by_kind.values())
        print(
            "share of the negative curvature: "
            + ", ".join(f"{k} {v / total:.1%}" for k, v in by_kind.items())
        )


if __name__ == "__main__":
    main()
