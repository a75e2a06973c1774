//! The numeric supernodal LDLᵀ factorisation and triangular solves of the
//! interior-point solver's KKT matrix, over the layout of faer's symbolic
//! supernodal factorisation, with the elimination tree split over two
//! threads.
//!
//! The factorisation is left-looking, as faer's: each supernode gathers the
//! updates of the descendants whose rows reach its columns, then factorises
//! its dense column block. What differs:
//! * the supernodes narrower than [`DENSE_KERNEL_MIN_COLUMNS`] factorise
//!   their blocks and send their updates by plain loops over contiguous
//!   columns (the jump's supernodes are mostly one or two columns wide,
//!   where faer's dense kernels cost more in setup than in arithmetic);
//!   wider ones use faer's blocked LDLᵀ and matrix product;
//! * a wide supernode gathers the updates of its narrow descendants in
//!   batches, each one matrix product over the union of the members' rows
//!   ([`BATCH_MIN_COLUMNS`]): a shooting QP's dense root takes the updates
//!   of thousands of one-column constraint rows;
//! * a supernode reads only its own descendants, so disjoint subtrees of the
//!   supernodal elimination tree factorise independently (the tree-level
//!   parallelism of sparse direct solvers): the subtrees below the top
//!   separators of the nested-dissection ordering are shared between two
//!   threads by their estimated work; each thread then gathers its
//!   subtrees' updates of the top supernodes into a buffer of its own, and
//!   the top supernodes run after both, on the buffers' sum. Small systems
//!   (the Hock–Schittkowski problems) stay on one thread;
//! * the triangular solves run through the same subtrees on the same two
//!   threads, the second a persistent one ([`Helper`]).
//!
//! The pivots are regularised as faer's `LdltRegularization` does: a pivot
//! of the wrong sign for its row (or, without signs, of magnitude at most
//! ε) becomes ±δ.

use super::helper::Helper;

/// Where the supernodes of faer's supernodal LDLᵀ factor keep their
/// values: supernode s holds columns `begin[s]..begin[s + 1]` of L (unit
/// lower, D on its diagonal) as a column-major block from `val_ptr[s]`,
/// of its columns' count plus as many rows as lie below the diagonal
/// block, `row_idx[row_ptr[s]..row_ptr[s + 1]]` (ascending), of the
/// system permuted by the symbolic factor's ordering.
pub(crate) struct FactorLayout {
    begin: Vec<usize>,
    row_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    val_ptr: Vec<usize>,
    /// The updates each supernode gathers: `updates[update_ptr[s]..
    /// update_ptr[s + 1]]` holds (d, first, end): descendant d's pattern
    /// rows `first..end` are columns of s.
    update_ptr: Vec<usize>,
    updates: Vec<(usize, usize, usize)>,
    /// Which thread factorises each supernode: 0 or 1 (disjoint subtrees),
    /// or [`TOP`] (after both).
    owner: Vec<u8>,
    /// Supernodes at least this wide use faer's dense kernels
    /// ([`DENSE_KERNEL_MIN_COLUMNS`]).
    pub(crate) dense_min: usize,
    /// Supernodes at least this wide gather their narrow descendants'
    /// updates in batches ([`BATCH_MIN_COLUMNS`]).
    pub(crate) batch_min: usize,
    /// The second thread, where two pay (None: one thread).
    helper: Option<Helper>,
    /// The top supernodes in order, with the offset and length of their
    /// blocks in a thread's buffer of updates from its subtrees.
    top: Vec<(usize, usize, usize)>,
    top_len: usize,
    scratch: [Scratch; 2],
}

/// Supernodes at least this wide factorise their dense block, and compute
/// their updates of their ancestors, with faer's blocked kernels.
pub(crate) const DENSE_KERNEL_MIN_COLUMNS: usize = 32;

/// Supernodes at least this wide gather the updates of their narrow
/// descendants in batches, each batch one matrix product over the union of
/// its members' rows, instead of a scattered subtraction per entry: the
/// 673-column root of a shooting QP's KKT system takes the updates of
/// 2,164 one-column constraint rows of about 350 entries each.
pub(crate) const BATCH_MIN_COLUMNS: usize = 32;

/// The columns of L one batch multiplies at most.
const BATCH_COLUMNS: usize = 64;

/// A batch's product may cost at most this many times the multiply-adds
/// of its members' plain loops (it runs about ten times faster per
/// multiply-add); a batch whose rows spread wider takes the loops.
const BATCH_WORK_RATIO: f64 = 4.0;

/// Supernodes factorised after both subtree sets.
const TOP: u8 = 2;

/// Estimated multiply-adds below which a factorisation stays on one thread
/// (about a millisecond: below it, the split's bookkeeping and a second
/// thread that spins for work cost more than they save).
const PARALLEL_MIN_WORK: f64 = 2e6;

struct Scratch {
    /// Local row of each global row in the supernode being factorised.
    map: Vec<usize>,
    /// One column of a descendant's update.
    column: Vec<f64>,
    /// D times the descendant's row of the target column.
    weights: Vec<f64>,
    /// faer's dense LDLᵀ workspace.
    dense: faer::dyn_stack::MemBuffer,
    /// This thread's updates of the top supernodes.
    top_updates: Vec<f64>,
    /// The batch of narrow descendants whose updates of a wide supernode
    /// are gathered by one matrix product ([`Batch`]).
    batch: Batch,
}

/// Narrow descendants (descendant, first pattern row that reaches the
/// target) waiting to update a wide supernode together, with the work
/// arrays of their product.
#[derive(Default)]
struct Batch {
    members: Vec<(usize, usize)>,
    /// Columns of L the members hold.
    columns: usize,
    /// Multiply-adds the members' updates cost by the plain loops.
    loop_work: f64,
    /// The union of the members' rows that reach the target, ascending.
    rows: Vec<usize>,
    /// Each global row's position in `rows` (usize::MAX outside it).
    position: Vec<usize>,
    /// The members' columns on `rows`, column-major (rows × columns).
    panel: Vec<f64>,
    /// The columns' pivots D.
    pivots: Vec<f64>,
    /// D times the panel's rows in the target's columns.
    weighted: Vec<f64>,
    /// The product of the panel and `weighted`ᵀ.
    product: Vec<f64>,
    /// Batches taken as products, products with rows below the target's
    /// columns, and batches left to the loops (the tests check that each
    /// ran).
    #[cfg(test)]
    counts: [usize; 3],
}

/// A pivot at `column` (in the factor's order) that is zero or not finite
/// after regularisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PivotError {
    pub column: usize,
}

/// faer's dynamic regularisation of one pivot.
#[inline]
fn regularise(d: f64, sign: i8, eps: f64, delta: f64) -> f64 {
    let small_or_negative = d <= eps;
    let minus_small_or_positive = d >= -eps;
    if sign == 1 && small_or_negative {
        delta
    } else if sign == -1 && minus_small_or_positive {
        -delta
    } else if small_or_negative && minus_small_or_positive {
        if d < 0.0 {
            -delta
        } else {
            delta
        }
    } else {
        d
    }
}

impl FactorLayout {
    /// The layout of faer's supernodal symbolic factor (None for a
    /// simplicial one), with the update lists and the two threads' shares
    /// of the elimination tree.
    pub(crate) fn of(
        symbolic: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    ) -> Option<FactorLayout> {
        Self::with_parallel_min_work(symbolic, PARALLEL_MIN_WORK)
    }

    /// [`FactorLayout::of`], two threads from `min_work` estimated
    /// multiply-adds on (tests use both paths on small systems).
    pub(crate) fn with_parallel_min_work(
        symbolic: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
        min_work: f64,
    ) -> Option<FactorLayout> {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        let s = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => return None,
            SymbolicCholeskyRaw::Supernodal(s) => s,
        };
        let ns = s.n_supernodes();
        if ns == 0 {
            return None;
        }
        let begin: Vec<usize> = s.supernode_begin()[..ns]
            .iter()
            .copied()
            .chain(std::iter::once(s.supernode_end()[ns - 1]))
            .collect();
        let row_ptr = s.col_ptr_for_row_idx().to_vec();
        let row_idx = s.row_idx().to_vec();
        let val_ptr = s.col_ptr_for_val().to_vec();
        let n = begin[ns];
        let mut supernode_of = vec![0usize; n];
        for sn in 0..ns {
            supernode_of[begin[sn]..begin[sn + 1]].fill(sn);
        }
        // Update lists: the runs of each supernode's pattern that fall in
        // one ancestor's columns (a parent's index exceeds its child's, so
        // descendants come first in index order).
        let mut runs: Vec<(usize, usize, usize, usize)> = Vec::new();
        for d in 0..ns {
            let pattern = &row_idx[row_ptr[d]..row_ptr[d + 1]];
            let mut first = 0;
            while first < pattern.len() {
                let t = supernode_of[pattern[first]];
                let end = first + pattern[first..].partition_point(|&r| r < begin[t + 1]);
                runs.push((t, d, first, end));
                first = end;
            }
        }
        let mut update_ptr = vec![0usize; ns + 1];
        for &(t, ..) in &runs {
            update_ptr[t + 1] += 1;
        }
        for t in 0..ns {
            update_ptr[t + 1] += update_ptr[t];
        }
        let mut fill = update_ptr.clone();
        let mut updates = vec![(0, 0, 0); runs.len()];
        for &(t, d, first, end) in &runs {
            updates[fill[t]] = (d, first, end);
            fill[t] += 1;
        }
        let parent: Vec<Option<usize>> = (0..ns)
            .map(|sn| (row_ptr[sn] < row_ptr[sn + 1]).then(|| supernode_of[row_idx[row_ptr[sn]]]))
            .collect();
        // Work estimate of a supernode of c columns and p rows below them:
        // its updates of its ancestors, c multiply-adds and one scattered
        // subtraction for each of the p(p + 1)/2 entries they reach, and
        // its dense block, c²(c/3 + p), counted at a fifth where faer's
        // kernels factorise it (the jump's 271-column root takes 0.36 ms,
        // against about 2 ms for each thread's subtrees). Counting the wide
        // supernodes' updates, also faer's products, at a fifth as well
        // split the jump's tree no better (its QPs 1–30, alternating runs:
        // 3.04–3.49 s against 2.96–3.46 s).
        let work: Vec<f64> = (0..ns)
            .map(|sn| {
                let c = begin[sn + 1] - begin[sn];
                let rate = if c >= DENSE_KERNEL_MIN_COLUMNS {
                    0.2
                } else {
                    1.0
                };
                let (c, p) = (c as f64, (row_ptr[sn + 1] - row_ptr[sn]) as f64);
                let reached = p * (p + 1.0) / 2.0;
                (c + 1.0) * reached + rate * c * c * (c / 3.0 + p)
            })
            .collect();
        let (owner, parallel) = split_tree(&parent, &work, min_work);
        let helper = if parallel { Helper::new() } else { None };
        let scratch = [(); 2].map(|_| Scratch {
            map: vec![0; n],
            column: Vec::new(),
            weights: Vec::new(),
            dense: faer::dyn_stack::MemBuffer::new(faer::dyn_stack::StackReq::EMPTY),
            top_updates: Vec::new(),
            batch: Batch {
                position: vec![usize::MAX; n],
                ..Default::default()
            },
        });
        let mut top = Vec::new();
        let mut top_len = 0;
        if helper.is_some() {
            for sn in (0..ns).filter(|&sn| owner[sn] == TOP) {
                let len = val_ptr[sn + 1] - val_ptr[sn];
                top.push((sn, top_len, len));
                top_len += len;
            }
        }
        Some(FactorLayout {
            begin,
            row_ptr,
            row_idx,
            val_ptr,
            update_ptr,
            updates,
            owner,
            dense_min: DENSE_KERNEL_MIN_COLUMNS,
            batch_min: BATCH_MIN_COLUMNS,
            helper,
            top,
            top_len,
            scratch,
        })
    }

    /// Batches gathered by both threads: as products, as products with
    /// rows below the target's columns, and by the loops.
    #[cfg(test)]
    pub(crate) fn batch_counts(&self) -> [usize; 3] {
        let [a, b] = &self.scratch;
        [0, 1, 2].map(|k| a.batch.counts[k] + b.batch.counts[k])
    }

    /// Whether the factorisation and the solves use a second thread.
    #[cfg(test)]
    pub(crate) fn parallel(&self) -> bool {
        self.helper.is_some()
    }

    /// The position in the factor's values of the entry (row, col) of the
    /// permuted matrix, row ≥ col, or None where the symbolic factor has
    /// no such entry.
    pub(crate) fn position(&self, row: usize, col: usize) -> Option<usize> {
        let sn = self.begin.partition_point(|&b| b <= col) - 1;
        let (start, end) = (self.begin[sn], self.begin[sn + 1]);
        let pattern = &self.row_idx[self.row_ptr[sn]..self.row_ptr[sn + 1]];
        let nc = end - start;
        let nr = nc + pattern.len();
        let local = if row < end {
            row - start
        } else {
            nc + pattern.binary_search(&row).ok()?
        };
        Some(self.val_ptr[sn] + (col - start) * nr + local)
    }

    /// Factorise in place: `values` holds the lower triangle of the
    /// permuted matrix in the factor's layout (zero elsewhere) and becomes
    /// L (unit diagonal not stored) with D on its diagonal. `signs` (in the
    /// factor's order) are the expected pivot signs of the dynamic
    /// regularisation; without them only pivots within ε of zero are
    /// regularised.
    pub(crate) fn factorise(
        &mut self,
        values: &mut [f64],
        signs: Option<&[i8]>,
        eps: f64,
        delta: f64,
    ) -> Result<(), PivotError> {
        let ns = self.begin.len() - 1;
        let mut blocks: Vec<&mut [f64]> = Vec::with_capacity(ns);
        let mut rest = values;
        for sn in 0..ns {
            let (block, tail) = rest.split_at_mut(self.val_ptr[sn + 1] - self.val_ptr[sn]);
            blocks.push(block);
            rest = tail;
        }
        let tree = Tree {
            begin: &self.begin,
            row_ptr: &self.row_ptr,
            row_idx: &self.row_idx,
            update_ptr: &self.update_ptr,
            updates: &self.updates,
            signs,
            eps,
            delta,
            dense_min: self.dense_min,
            batch_min: self.batch_min,
        };
        let [s0, s1] = &mut self.scratch;
        let Some(helper) = &mut self.helper else {
            return (0..ns).try_for_each(|sn| tree.supernode(sn, &mut blocks, s0, None));
        };
        let owner = &self.owner[..];
        let top = &self.top[..];
        let mut own: [Vec<&mut [f64]>; 2] = [0, 1].map(|_| {
            let mut v: Vec<&mut [f64]> = Vec::with_capacity(ns);
            v.resize_with(ns, Default::default);
            v
        });
        for (sn, block) in blocks.iter_mut().enumerate() {
            if owner[sn] != TOP {
                own[owner[sn] as usize][sn] = std::mem::take(block);
            }
        }
        // Each thread factorises its subtrees, then gathers their updates
        // into the top supernodes, in a buffer of its own.
        let run = |who: u8, blocks: &mut Vec<&mut [f64]>, scratch: &mut Scratch| {
            (0..ns)
                .filter(|&sn| owner[sn] == who)
                .try_for_each(|sn| tree.supernode(sn, blocks, scratch, None))?;
            let mut buffer = std::mem::take(&mut scratch.top_updates);
            buffer.clear();
            buffer.resize(self.top_len, 0.0);
            for &(t, offset, len) in top {
                tree.gather(
                    t,
                    &mut buffer[offset..offset + len],
                    blocks,
                    scratch,
                    Some((owner, who)),
                );
            }
            scratch.top_updates = buffer;
            Ok(())
        };
        let [own0, own1] = &mut own;
        let mut r1 = Ok(());
        // A panic of the second thread's half (a bug) reads as a failed
        // factorisation, which the solver reports, not as a crash.
        let (r0, returned) = helper.join(&mut || r1 = run(1, own1, s1), || run(0, own0, s0));
        if !returned {
            r1 = Err(PivotError { column: 0 });
        }
        r0?;
        r1?;
        for (sn, block) in blocks.iter_mut().enumerate() {
            if owner[sn] != TOP {
                *block = std::mem::take(&mut own[owner[sn] as usize][sn]);
            }
        }
        for &(t, offset, len) in top {
            let (u0, u1) = (
                &s0.top_updates[offset..offset + len],
                &s1.top_updates[offset..offset + len],
            );
            for ((v, a), b) in blocks[t].iter_mut().zip(u0).zip(u1) {
                *v += a + b;
            }
            tree.supernode(t, &mut blocks, s0, Some((owner, TOP)))?;
        }
        Ok(())
    }

    /// Solve L D Lᵀ x = v in place (x, v in the factor's order). The
    /// supernodes of a transcription's KKT system are mostly a column or
    /// two wide, where plain loops beat faer's dense kernels (measured:
    /// LEAP's QP set, `examples/ipm_bench`). With two threads, each
    /// substitutes through its subtrees (forward: its updates of the top
    /// rows in a vector of its own, added after), and the top supernodes
    /// run in between.
    pub(crate) fn solve(&mut self, values: &[f64], x: &mut [f64], scratch: &mut SolveScratch) {
        let ns = self.begin.len() - 1;
        let SolveScratch { work: [w0, w1], x1 } = scratch;
        let tree = Substitution {
            begin: &self.begin,
            row_ptr: &self.row_ptr,
            row_idx: &self.row_idx,
            val_ptr: &self.val_ptr,
            values,
        };
        let owner = &self.owner[..];
        let Some(helper) = &mut self.helper else {
            (0..ns).for_each(|sn| tree.forward(sn, x, w0));
            tree.diagonal(x);
            (0..ns).rev().for_each(|sn| tree.backward(sn, x, w0));
            return;
        };
        let mine = |who: u8| (0..ns).filter(move |&sn| owner[sn] == who);
        // The second thread's vector: its columns, zero on the top ones.
        x1.clear();
        x1.resize(x.len(), 0.0);
        for sn in mine(1) {
            let cols = self.begin[sn]..self.begin[sn + 1];
            x1[cols.clone()].copy_from_slice(&x[cols]);
        }
        let (_, returned) = helper.join(
            &mut || mine(1).for_each(|sn| tree.forward(sn, x1, w1)),
            || mine(0).for_each(|sn| tree.forward(sn, x, w0)),
        );
        for sn in 0..ns {
            let cols = self.begin[sn]..self.begin[sn + 1];
            match owner[sn] {
                1 => x[cols.clone()].copy_from_slice(&x1[cols]),
                TOP => x[cols.clone()]
                    .iter_mut()
                    .zip(&x1[cols])
                    .for_each(|(a, b)| *a += b),
                _ => {}
            }
        }
        mine(TOP).for_each(|sn| tree.forward(sn, x, w0));
        tree.diagonal(x);
        for sn in (0..ns).rev().filter(|&sn| owner[sn] == TOP) {
            tree.backward(sn, x, w0);
        }
        // The second thread reads the top rows and writes its own.
        x1.copy_from_slice(x);
        let (_, returned_too) = helper.join(
            &mut || {
                for sn in (0..ns).rev().filter(|&sn| owner[sn] == 1) {
                    tree.backward(sn, x1, w1);
                }
            },
            || {
                for sn in (0..ns).rev().filter(|&sn| owner[sn] == 0) {
                    tree.backward(sn, x, w0);
                }
            },
        );
        for sn in mine(1) {
            let cols = self.begin[sn]..self.begin[sn + 1];
            x[cols.clone()].copy_from_slice(&x1[cols]);
        }
        if !(returned && returned_too) {
            // A bug in the second thread's half: NaN, which the solver's
            // residual checks report.
            x.fill(f64::NAN);
        }
    }
}

/// The vectors of [`FactorLayout::solve`], kept between calls: each
/// thread's gathered rows, the second thread's copy of x.
#[derive(Default)]
pub(crate) struct SolveScratch {
    work: [Vec<f64>; 2],
    x1: Vec<f64>,
}

/// The triangular solves' view of a factor.
struct Substitution<'a> {
    begin: &'a [usize],
    row_ptr: &'a [usize],
    row_idx: &'a [usize],
    val_ptr: &'a [usize],
    values: &'a [f64],
}

impl Substitution<'_> {
    /// The block of supernode `sn`: (first column, columns, rows below the
    /// diagonal block, values).
    #[inline]
    fn block(&self, sn: usize) -> (usize, usize, &[usize], &[f64]) {
        let (start, nc) = (self.begin[sn], self.begin[sn + 1] - self.begin[sn]);
        let below = &self.row_idx[self.row_ptr[sn]..self.row_ptr[sn + 1]];
        let nr = nc + below.len();
        (
            start,
            nc,
            below,
            &self.values[self.val_ptr[sn]..self.val_ptr[sn] + nr * nc],
        )
    }

    /// Forward substitution through supernode `sn`: its columns of x
    /// solved, the rows below updated. The rows below are accumulated in
    /// the contiguous `work`, so that the inner loops run over contiguous
    /// memory (the jump's widest supernode has 271 columns).
    fn forward(&self, sn: usize, x: &mut [f64], work: &mut Vec<f64>) {
        let (start, nc, below, block) = self.block(sn);
        let nr = nc + below.len();
        let (xs, _) = x[start..].split_at_mut(nc);
        work.clear();
        work.resize(below.len(), 0.0);
        let mut any = false;
        for j in 0..nc {
            let col = &block[j * nr..(j + 1) * nr];
            let xj = xs[j];
            if xj == 0.0 {
                continue;
            }
            any = true;
            for (xi, l) in xs[j + 1..].iter_mut().zip(&col[j + 1..nc]) {
                *xi -= l * xj;
            }
            for (w, l) in work.iter_mut().zip(&col[nc..]) {
                *w += l * xj;
            }
        }
        if any {
            for (&r, w) in below.iter().zip(work.iter()) {
                x[r] -= w;
            }
        }
    }

    /// x ← D⁻¹ x.
    fn diagonal(&self, x: &mut [f64]) {
        for sn in 0..self.begin.len() - 1 {
            let (start, nc, below, block) = self.block(sn);
            let nr = nc + below.len();
            for j in 0..nc {
                x[start + j] /= block[j * nr + j];
            }
        }
    }

    /// Backward substitution through supernode `sn`: its columns of x
    /// solved from the rows below (gathered into `work`).
    fn backward(&self, sn: usize, x: &mut [f64], work: &mut Vec<f64>) {
        let (start, nc, below, block) = self.block(sn);
        let nr = nc + below.len();
        work.clear();
        work.extend(below.iter().map(|&r| x[r]));
        let xs = &mut x[start..start + nc];
        for j in (0..nc).rev() {
            let col = &block[j * nr..(j + 1) * nr];
            xs[j] -= dot(&col[nc..], work) + dot(&col[j + 1..nc], &xs[j + 1..]);
        }
    }
}

/// Assign each supernode to thread 0 or 1 or to the top, minimising the
/// estimated time: the top's work plus the larger thread's. Starting from
/// the roots, the heaviest subtree root moves to the top and its children
/// become subtrees, while that lowers the estimate. Returns the owners and
/// whether two threads pay (against one thread's total work).
fn split_tree(parent: &[Option<usize>], work: &[f64], min_work: f64) -> (Vec<u8>, bool) {
    let ns = parent.len();
    let mut subtree = work.to_vec();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
    for sn in 0..ns {
        if let Some(p) = parent[sn] {
            subtree[p] += subtree[sn];
            children[p].push(sn);
        }
    }
    let total: f64 = work.iter().sum();
    let sequential = (vec![0u8; ns], false);
    if total < min_work {
        return sequential;
    }
    // Longest-processing-time assignment of the frontier's subtrees.
    let assign = |frontier: &[usize]| {
        let mut sorted = frontier.to_vec();
        sorted.sort_by(|&a, &b| subtree[b].total_cmp(&subtree[a]));
        let mut load = [0.0f64; 2];
        let mut bins = Vec::with_capacity(sorted.len());
        for sn in sorted {
            let bin = usize::from(load[1] < load[0]);
            load[bin] += subtree[sn];
            bins.push((sn, bin as u8));
        }
        (load[0].max(load[1]), bins)
    };
    let mut frontier: Vec<usize> = (0..ns).filter(|&sn| parent[sn].is_none()).collect();
    let mut top: Vec<usize> = Vec::new();
    let mut top_work = 0.0;
    let mut best = (f64::INFINITY, Vec::new(), Vec::new());
    for _ in 0..ns.min(256) {
        let (longest, bins) = assign(&frontier);
        if top_work + longest < best.0 {
            best = (top_work + longest, bins, top.clone());
        }
        let Some((k, _)) = frontier
            .iter()
            .enumerate()
            .max_by(|a, b| subtree[*a.1].total_cmp(&subtree[*b.1]))
        else {
            break;
        };
        let sn = frontier.swap_remove(k);
        top.push(sn);
        top_work += work[sn];
        frontier.extend(&children[sn]);
    }
    let (estimate, bins, top) = best;
    // Two threads must save a fifth of the work to pay for their start.
    if estimate > 0.8 * total {
        return sequential;
    }
    let mut owner = vec![u8::MAX; ns];
    for sn in top {
        owner[sn] = TOP;
    }
    for (sn, bin) in bins {
        owner[sn] = bin;
    }
    for sn in (0..ns).rev() {
        if owner[sn] == u8::MAX {
            // A parent's index exceeds its child's: set already.
            owner[sn] = parent[sn].map_or(0, |p| owner[p]);
        }
    }
    (owner, true)
}

/// The read-only parts of a factorisation, shared by both threads.
struct Tree<'a> {
    begin: &'a [usize],
    row_ptr: &'a [usize],
    row_idx: &'a [usize],
    update_ptr: &'a [usize],
    updates: &'a [(usize, usize, usize)],
    signs: Option<&'a [i8]>,
    eps: f64,
    delta: f64,
    /// Supernodes at least this wide use faer's kernels, for their dense
    /// block and their updates ([`DENSE_KERNEL_MIN_COLUMNS`]; the tests
    /// set 1 and usize::MAX to check both paths).
    dense_min: usize,
    /// Supernodes at least this wide batch their narrow descendants'
    /// updates ([`BATCH_MIN_COLUMNS`]; the tests set 1 and usize::MAX).
    batch_min: usize,
}

impl Tree<'_> {
    /// Gather the updates of supernode `sn`'s descendants into its block,
    /// then factorise the block. `blocks[d]` holds every descendant d's
    /// finished columns (owned by the caller's thread, or all of them for
    /// the top).
    fn supernode(
        &self,
        sn: usize,
        blocks: &mut [&mut [f64]],
        scratch: &mut Scratch,
        from: Option<(&[u8], u8)>,
    ) -> Result<(), PivotError> {
        let (done, rest) = blocks.split_at_mut(sn);
        let target: &mut [f64] = &mut *rest[0];
        self.gather(sn, target, done, scratch, from);
        self.block(sn, target, scratch)
    }

    /// Subtract from `target` (supernode `sn`'s block, or a buffer of its
    /// shape) the updates of its descendants, of those whose owner is
    /// `from.1` where given; `done[d]` holds descendant d's columns.
    fn gather(
        &self,
        sn: usize,
        target: &mut [f64],
        done: &[&mut [f64]],
        scratch: &mut Scratch,
        from: Option<(&[u8], u8)>,
    ) {
        let (start, end) = (self.begin[sn], self.begin[sn + 1]);
        let nc = end - start;
        let pattern = &self.row_idx[self.row_ptr[sn]..self.row_ptr[sn + 1]];
        let nr = nc + pattern.len();
        for (i, &row) in pattern.iter().enumerate() {
            scratch.map[row] = nc + i;
        }
        let batched = nc >= self.batch_min;
        for &(d, first, last) in &self.updates[self.update_ptr[sn]..self.update_ptr[sn + 1]] {
            if from.is_some_and(|(owner, who)| owner[d] != who) {
                continue;
            }
            let ncd = self.begin[d + 1] - self.begin[d];
            let pd = &self.row_idx[self.row_ptr[d]..self.row_ptr[d + 1]];
            if ncd >= self.dense_min {
                self.gather_dense(
                    &*done[d],
                    ncd,
                    &pd[first..],
                    last - first,
                    target,
                    nr,
                    sn,
                    scratch,
                );
                continue;
            }
            if batched {
                let b = &mut scratch.batch;
                b.members.push((d, first));
                b.columns += ncd;
                let (p, k) = ((pd.len() - first) as f64, (last - first) as f64);
                b.loop_work += ncd as f64 * k * (p - (k - 1.0) / 2.0);
                if b.columns >= BATCH_COLUMNS {
                    self.flush_batch(sn, target, done, scratch);
                }
                continue;
            }
            self.gather_narrow(d, first, last, &*done[d], target, nr, sn, scratch);
        }
        if batched {
            self.flush_batch(sn, target, done, scratch);
        }
    }

    /// The target's row (in supernode `sn`'s block) of a global row: one
    /// of its columns, or a row of its pattern through `map`.
    #[inline]
    fn local(&self, sn: usize, map: &[usize], row: usize) -> usize {
        let (start, end) = (self.begin[sn], self.begin[sn + 1]);
        if row < end {
            row - start
        } else {
            map[row]
        }
    }

    /// Subtract from `target` (supernode `sn`'s block, `nr` rows per
    /// column) the update of the narrow descendant d (values `ld`) whose
    /// pattern rows `first..last` are its columns, by plain loops.
    #[allow(clippy::too_many_arguments)]
    fn gather_narrow(
        &self,
        d: usize,
        first: usize,
        last: usize,
        ld: &[f64],
        target: &mut [f64],
        nr: usize,
        sn: usize,
        scratch: &mut Scratch,
    ) {
        let start = self.begin[sn];
        let ncd = self.begin[d + 1] - self.begin[d];
        let pd = &self.row_idx[self.row_ptr[d]..self.row_ptr[d + 1]];
        let nrd = ncd + pd.len();
        for jj in first..last {
            let col = (pd[jj] - start) * nr;
            let rows = &pd[jj..];
            if ncd == 1 {
                let w = ld[0] * ld[1 + jj];
                if w != 0.0 {
                    for (&row, l) in rows.iter().zip(&ld[1 + jj..]) {
                        target[col + self.local(sn, &scratch.map, row)] -= w * l;
                    }
                }
                continue;
            }
            let weights = &mut scratch.weights;
            weights.clear();
            weights.extend((0..ncd).map(|k| ld[k * nrd + k] * ld[k * nrd + ncd + jj]));
            let column = &mut scratch.column;
            column.clear();
            column.resize(rows.len(), 0.0);
            for (k, &w) in weights.iter().enumerate() {
                if w != 0.0 {
                    let lk = &ld[k * nrd + ncd + jj..(k + 1) * nrd];
                    for (c, l) in column.iter_mut().zip(lk) {
                        *c += w * l;
                    }
                }
            }
            for (&row, c) in rows.iter().zip(column.iter()) {
                target[col + self.local(sn, &scratch.map, row)] -= c;
            }
        }
    }

    /// Subtract from `target` (supernode `sn`'s block) the updates of the
    /// batch's members as one product: their columns on the union of
    /// their rows form a panel V (D their pivots), and the update is
    /// V·(V_c·D)ᵀ, V_c the panel's rows in the target's columns (lower
    /// triangle only), scattered once. A batch whose product would cost
    /// more than [`BATCH_WORK_RATIO`] times its loops takes the loops.
    fn flush_batch(
        &self,
        sn: usize,
        target: &mut [f64],
        done: &[&mut [f64]],
        scratch: &mut Scratch,
    ) {
        use faer::linalg::matmul::triangular::{matmul, BlockStructure};
        use faer::{Accum, MatMut, MatRef, Par};
        let end = self.begin[sn + 1];
        let nc = end - self.begin[sn];
        let nr = nc + self.row_ptr[sn + 1] - self.row_ptr[sn];
        if scratch.batch.members.is_empty() {
            return;
        }
        let mut b = std::mem::take(&mut scratch.batch);
        let pattern_of = |d: usize| &self.row_idx[self.row_ptr[d]..self.row_ptr[d + 1]];
        b.rows.clear();
        for &(d, first) in &b.members {
            for &row in &pattern_of(d)[first..] {
                if b.position[row] == usize::MAX {
                    b.position[row] = 0;
                    b.rows.push(row);
                }
            }
        }
        b.rows.sort_unstable();
        let (u, k) = (b.rows.len(), b.columns);
        let uc = b.rows.partition_point(|&r| r < end);
        // The product's multiply-adds: the lower triangle of its top
        // uc × uc block and the rows below it.
        let (uf, ucf) = (u as f64, uc as f64);
        let product_work = k as f64 * (ucf * (ucf + 1.0) / 2.0 + (uf - ucf) * ucf);
        #[cfg(test)]
        {
            let kind = if product_work > BATCH_WORK_RATIO * b.loop_work {
                2
            } else {
                usize::from(u > uc)
            };
            b.counts[kind] += 1;
        }
        if product_work > BATCH_WORK_RATIO * b.loop_work {
            for &row in &b.rows {
                b.position[row] = usize::MAX;
            }
            for &(d, first) in &b.members {
                let pd = pattern_of(d);
                let last = first + pd[first..].partition_point(|&r| r < end);
                self.gather_narrow(d, first, last, &*done[d], target, nr, sn, scratch);
            }
        } else {
            for (i, &row) in b.rows.iter().enumerate() {
                b.position[row] = i;
            }
            b.panel.clear();
            b.panel.resize(u * k, 0.0);
            b.pivots.clear();
            for &(d, first) in &b.members {
                let (ld, pd) = (&*done[d], pattern_of(d));
                let ncd = self.begin[d + 1] - self.begin[d];
                let nrd = ncd + pd.len();
                for c in 0..ncd {
                    let column = b.pivots.len();
                    b.pivots.push(ld[c * nrd + c]);
                    let panel = &mut b.panel[column * u..(column + 1) * u];
                    for (&row, &l) in pd[first..].iter().zip(&ld[c * nrd + ncd + first..]) {
                        panel[b.position[row]] = l;
                    }
                }
            }
            b.weighted.clear();
            b.weighted.resize(uc * k, 0.0);
            for (c, &dc) in b.pivots.iter().enumerate() {
                for (w, &v) in b.weighted[c * uc..(c + 1) * uc]
                    .iter_mut()
                    .zip(&b.panel[c * u..c * u + uc])
                {
                    *w = v * dc;
                }
            }
            b.product.clear();
            b.product.resize(u * uc, 0.0);
            let v = MatRef::from_column_major_slice(&b.panel, u, k);
            let w = MatRef::from_column_major_slice(&b.weighted, uc, k);
            let product = MatMut::from_column_major_slice_mut(&mut b.product, u, uc);
            let (top, bottom) = product.split_at_row_mut(uc);
            matmul(
                top,
                BlockStructure::TriangularLower,
                Accum::Replace,
                v.subrows(0, uc),
                BlockStructure::Rectangular,
                w.transpose(),
                BlockStructure::Rectangular,
                1.0,
                Par::Seq,
            );
            if u > uc {
                faer::linalg::matmul::matmul(
                    bottom,
                    Accum::Replace,
                    v.subrows(uc, u - uc),
                    w.transpose(),
                    1.0,
                    Par::Seq,
                );
            }
            self.scatter_lower(sn, &scratch.map, &b.rows, uc, &b.product, target, nr);
            for &row in &b.rows {
                b.position[row] = usize::MAX;
            }
        }
        b.members.clear();
        b.columns = 0;
        b.loop_work = 0.0;
        scratch.batch = b;
    }

    /// Factorise supernode `sn`'s block, its updates gathered.
    fn block(
        &self,
        sn: usize,
        target: &mut [f64],
        scratch: &mut Scratch,
    ) -> Result<(), PivotError> {
        let start = self.begin[sn];
        let nc = self.begin[sn + 1] - start;
        let nr = nc + self.row_ptr[sn + 1] - self.row_ptr[sn];
        if nc >= self.dense_min {
            return self.dense_faer(start, nc, nr, target, scratch);
        }
        // The dense block: right-looking LDLᵀ over its columns, rows below
        // the diagonal block included.
        for j in 0..nc {
            let sign = self.signs.map_or(0, |s| s[start + j]);
            let d = regularise(target[j * nr + j], sign, self.eps, self.delta);
            if d == 0.0 || !d.is_finite() {
                return Err(PivotError { column: start + j });
            }
            target[j * nr + j] = d;
            let inv = 1.0 / d;
            let (left, right) = target.split_at_mut((j + 1) * nr);
            let colj = &mut left[j * nr..];
            for k in j + 1..nc {
                let f = colj[k] * inv;
                if f != 0.0 {
                    let ck = &mut right[(k - j - 1) * nr + k..(k - j) * nr];
                    for (c, a) in ck.iter_mut().zip(&colj[k..]) {
                        *c -= f * a;
                    }
                }
            }
            for a in colj[j + 1..].iter_mut() {
                *a *= inv;
            }
        }
        Ok(())
    }
}

impl Tree<'_> {
    /// Subtract from `target` (rows `nr` per column) the update of a wide
    /// descendant (`ncd` columns, values `ld`) whose pattern rows `rows`
    /// reach it, the first `k` of them its columns: the product
    /// L_rows·D·L_firstᵀ by faer's matrix product, then scattered through
    /// `local` (the target's row of a global row).
    #[allow(clippy::too_many_arguments)]
    fn gather_dense(
        &self,
        ld: &[f64],
        ncd: usize,
        rows: &[usize],
        k: usize,
        target: &mut [f64],
        nr: usize,
        sn: usize,
        scratch: &mut Scratch,
    ) {
        use faer::{Accum, MatMut, MatRef, Par};
        let (m, nrd) = (rows.len(), ld.len() / ncd);
        let first = nrd - m;
        let l = MatRef::from_column_major_slice(ld, nrd, ncd);
        let below = l.subrows(first, m);
        // W = L_first·D, k × ncd.
        let weights = &mut scratch.weights;
        weights.clear();
        weights.resize(k * ncd, 0.0);
        let mut w = MatMut::from_column_major_slice_mut(weights, k, ncd);
        for c in 0..ncd {
            let dc = l[(c, c)];
            for j in 0..k {
                w[(j, c)] = below[(j, c)] * dc;
            }
        }
        let column = &mut scratch.column;
        column.clear();
        column.resize(m * k, 0.0);
        faer::linalg::matmul::matmul(
            MatMut::from_column_major_slice_mut(column, m, k),
            Accum::Replace,
            below,
            w.as_ref().transpose(),
            1.0,
            Par::Seq,
        );
        self.scatter_lower(sn, &scratch.map, rows, k, &scratch.column, target, nr);
    }

    /// Subtract from `target` (supernode `sn`'s block, `nr` rows per
    /// column) the lower triangle of an update over the global `rows`, the
    /// first `k` of them the target's columns: `product` is column-major,
    /// `rows.len()` × k.
    #[allow(clippy::too_many_arguments)]
    fn scatter_lower(
        &self,
        sn: usize,
        map: &[usize],
        rows: &[usize],
        k: usize,
        product: &[f64],
        target: &mut [f64],
        nr: usize,
    ) {
        let m = rows.len();
        for j in 0..k {
            let col = self.local(sn, map, rows[j]) * nr;
            let pj = &product[j * m..(j + 1) * m];
            for i in j..m {
                target[col + self.local(sn, map, rows[i])] -= pj[i];
            }
        }
    }

    /// The dense block of a wide supernode by faer's blocked kernels: LDLᵀ
    /// of the diagonal block, then the rows below by a triangular solve
    /// and D⁻¹ (as faer's supernodal factorisation does).
    fn dense_faer(
        &self,
        start: usize,
        nc: usize,
        nr: usize,
        target: &mut [f64],
        scratch: &mut Scratch,
    ) -> Result<(), PivotError> {
        use faer::linalg::cholesky::ldlt::factor::{
            cholesky_in_place, cholesky_in_place_scratch, LdltRegularization,
        };
        use faer::reborrow::{Reborrow, ReborrowMut};
        use faer::{dyn_stack::MemBuffer, dyn_stack::MemStack, MatMut, Par};
        let req = cholesky_in_place_scratch::<f64>(nc, Par::Seq, Default::default());
        if scratch.dense.len() < req.size_bytes() {
            scratch.dense = MemBuffer::new(req);
        }
        let ls = MatMut::from_column_major_slice_mut(&mut target[..nr * nc], nr, nc);
        let (mut top, mut bottom) = ls.split_at_row_mut(nc);
        let reg = LdltRegularization {
            dynamic_regularization_signs: self.signs.map(|s| &s[start..start + nc]),
            dynamic_regularization_delta: self.delta,
            dynamic_regularization_epsilon: self.eps,
        };
        cholesky_in_place(
            top.rb_mut(),
            reg,
            Par::Seq,
            MemStack::new(&mut scratch.dense),
            Default::default(),
        )
        .map_err(|e| match e {
            faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => PivotError {
                column: start + index,
            },
        })?;
        for j in 1..nc {
            for i in 0..j {
                top[(i, j)] = 0.0;
            }
        }
        if nr > nc {
            faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
                top.rb(),
                bottom.rb_mut().transpose_mut(),
                Par::Seq,
            );
            for j in 0..nc {
                let inv = 1.0 / top[(j, j)];
                for i in 0..nr - nc {
                    bottom[(i, j)] *= inv;
                }
            }
        }
        Ok(())
    }
}

/// Σ a_i b_i over the shorter of the two, in four independent sums (a
/// single running sum waits on each addition's latency).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ac
        .remainder()
        .iter()
        .zip(bc.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ac.zip(bc) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}
