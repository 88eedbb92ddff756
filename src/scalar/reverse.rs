//! [`Rev`]: reverse-mode differentiation on a per-thread tape (the Adept / echidna pattern).
//!
//! A `Rev` is a `Copy` handle: its primal value and the index of the tape node that computed it (or a
//! marker for a constant, or the gradient entry of a scene parameter it was lifted from). Each operation
//! on non-constant operands appends one node to the calling thread's tape, recording its operands and
//! the local partials from [`super::rules`], the same table the forward-mode types read, so forward and
//! reverse rules cannot drift apart. Operations on constants record nothing.
//!
//! One sample of an estimator is recorded, turned into one scalar (the sample's share of
//! `Σ_pixels g · I`), and swept backwards once ([`Recording::sweep`]): every node's adjoint times its
//! partials flows to its operands, and parameter operands hand their share to the caller. The tape is
//! then rewound for the next sample. A grid's B-spline sum is one node ([`Scalar::lattice_sum`]), so grids
//! of hundreds of thousands of values cost no leaves; its 64 values are not operands but one
//! [`LatticeRecord`] beside the node (the taps and their weights): the values are parameters, whose
//! shares no other node needs, so they are expanded after the sweep, once per point for the value and
//! the gradient of a lookup together (the four sums of a `Grad<Rev>` lookup share one set of taps).
//!
//! A tape belongs to a thread, so a [`Recording`] must not be interleaved with another on the same thread
//! (as when a rayon task, started from inside a recording, is stolen by the recording thread):
//! [`Recording::start`] refuses to start while one is active.

use super::lattice::{LatticeTaps, lattice_sum_f32, lattice_sums_with_derivatives_f32};
use super::{Scalar, Slot, rules};
use std::cell::{Cell, RefCell};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The index of a constant.
const CONSTANT: u32 = u32::MAX;
/// The flag of a parameter reference: `PARAM | k` is gradient entry `k`.
const PARAM: u32 = 1 << 31;
/// The largest gradient entry a parameter may have.
pub const MAX_GRADIENT_ENTRY: u32 = PARAM - 2;

/// A reverse-mode number: a primal value and where it came from (a tape node, a parameter, or nowhere).
///
/// Comparisons in [`Scalar`]'s defaults look at the primal only, as for every scalar type. Values must
/// not outlive the sample (the [`Recording::rewind`]) they were computed in.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Rev {
    v: f32,
    i: u32,
}

/// One thread's tape: one buffer in which each node is its operands (node index or `PARAM | entry`,
/// with its partial) followed by a header holding their count and the node's adjoint (0 outside a
/// sweep); a node's index is its header's position. One push per operand and one per node into one
/// buffer, and the sweep walks it backwards, reading each node's operands from the same cache lines
/// as its header and accumulating adjoints in place (no array to clear per sweep).
struct Tape {
    entries: Vec<(u32, f32)>,
    lattices: Vec<LatticeRecord>,
    active: bool,
}

/// The block operands of a [`Scalar::lattice_sum`] node: value `(iz[c]·ny + iy[b])·nx + ix[a]` of the
/// block starting at gradient entry `first` has partial `wz[c]·wy[b]·wx[a]`.
#[derive(Copy, Clone, Debug)]
struct LatticeRecord {
    node: u32,
    /// The node's adjoint, set by the sweep that reached it.
    adjoint: f32,
    first: u32,
    nx: u32,
    ny: u32,
    index: [[u32; 4]; 3],
    weight: [[f32; 4]; 3],
}

impl LatticeRecord {
    /// The record of node `node` over the taps `index` of a lattice of `dims` (`count` values) whose
    /// first value is gradient entry `first`, with the weights `weight`.
    #[inline(always)]
    fn new(
        node: u32,
        first: u32,
        (dims, count): ([usize; 3], usize),
        index: [[usize; 4]; 3],
        weight: [[f32; 4]; 3],
    ) -> Self {
        debug_assert!(
            first as usize + count - 1 <= MAX_GRADIENT_ENTRY as usize,
            "the block's gradient entries overflow"
        );
        Self {
            node,
            adjoint: 0.0,
            first,
            nx: dims[0] as u32,
            ny: dims[1] as u32,
            index: index.map(|axis| axis.map(|k| k as u32)),
            weight,
        }
    }

    /// Whether the two records address the same 64 values.
    #[inline]
    fn same_taps(&self, o: &Self) -> bool {
        (self.first, self.nx, self.ny, self.index) == (o.first, o.nx, o.ny, o.index)
    }
}

thread_local! {
    static TAPE: RefCell<Tape> = const {
        RefCell::new(Tape {
            entries: Vec::new(),
            lattices: Vec::new(),
            active: false,
        })
    };
}

thread_local! {
    /// This thread's tape while a recording is active and no borrow of [`TAPE`] is alive (null
    /// otherwise): what the recording of one operation reads, one thread-local access with neither
    /// a destructor's state nor a borrow flag to check.
    static ACTIVE: Cell<*mut Tape> = const { Cell::new(std::ptr::null_mut()) };
}

/// Runs `f` on this thread's tape: through [`ACTIVE`] during a recording, else through the
/// `RefCell` (which then refuses a nested borrow, as during a sweep's callback).
#[inline(always)]
fn with_tape<R>(f: impl FnOnce(&mut Tape) -> R) -> R {
    let active = ACTIVE.with(Cell::get);
    if active.is_null() {
        TAPE.with(|t| f(&mut t.borrow_mut()))
    } else {
        // SAFETY: `ACTIVE` points into this thread's `TAPE` (alive as long as the thread) only
        // between `Recording::start` and the recording's drop, and `Recording::sweep` clears it
        // while it holds the `RefCell`'s borrow; every `f` here is this module's own bookkeeping,
        // which calls no code that could reach the tape again, so this is its only reference.
        f(unsafe { &mut *active })
    }
}

impl Tape {
    /// Closes the node whose operands were pushed since `start` (the entries' length before them).
    #[inline(always)]
    fn node(&mut self, start: usize) -> u32 {
        let i = self.entries.len();
        self.entries.push(((i - start) as u32, 0.0));
        i as u32
    }
    #[inline(always)]
    fn operand(&mut self, target: u32, partial: f32) {
        self.entries.push((target, partial));
    }
}

impl Rev {
    /// A constant.
    #[inline(always)]
    pub const fn new(v: f32) -> Self {
        Self { v, i: CONSTANT }
    }

    /// The parameter with gradient entry `entry` (at most [`MAX_GRADIENT_ENTRY`]) and value `v`.
    #[inline(always)]
    pub fn parameter(v: f32, entry: u32) -> Self {
        assert!(
            entry <= MAX_GRADIENT_ENTRY,
            "gradient entry {entry} out of range"
        );
        Self {
            v,
            i: PARAM | entry,
        }
    }

    /// Whether this value depends on nothing recorded.
    #[inline(always)]
    pub fn is_constant(self) -> bool {
        self.i == CONSTANT
    }

    /// A node with value `v` and operands `(x, ∂/∂x)`; a constant if every operand is.
    #[inline(always)]
    fn record(v: f32, operands: &[(Rev, f32)]) -> Self {
        if operands.iter().all(|(x, _)| x.i == CONSTANT) {
            return Self::new(v);
        }
        with_tape(|t| {
            let start = t.entries.len();
            for &(x, d) in operands {
                if x.i != CONSTANT {
                    t.operand(x.i, d);
                }
            }
            let i = t.node(start);
            Self { v, i }
        })
    }

    #[inline(always)]
    fn unary(self, (v, d): (f32, f32)) -> Self {
        Self::record(v, &[(self, d)])
    }

    #[inline(always)]
    fn binary(self, o: Self, (v, dx, dy): (f32, f32, f32)) -> Self {
        Self::record(v, &[(self, dx), (o, dy)])
    }

    /// `Σ_k c_k x_k` as one node (e.g. a sample's share of `Σ_pixels g · I`).
    pub fn linear_combination(terms: &[(Rev, f32)]) -> Self {
        let v = terms.iter().fold(0.0, |acc, &(x, c)| acc + c * x.v);
        Self::record(v, terms)
    }
}

/// The recording on this thread's tape: while it lives, [`Rev`] operations on this thread are recorded;
/// [`Recording::mark`], [`Recording::rewind`] and [`Recording::sweep`] act on the tape of the calling
/// thread's active recording. Dropping it clears the tape.
///
/// Not `Send`: it belongs to the thread whose tape it holds.
pub struct Recording {
    _thread: std::marker::PhantomData<*const ()>,
}

/// A position on the tape to rewind to ([`Recording::mark`]).
#[derive(Copy, Clone, Debug, Default)]
pub struct Mark {
    entries: usize,
    lattices: usize,
}

impl Recording {
    /// Starts recording on this thread with an empty tape.
    ///
    /// Panics if a recording is already active on this thread: two interleaved recordings would
    /// corrupt each other's tape (a parallel task must not start inside a recording).
    pub fn start() -> Self {
        TAPE.with(|cell| {
            let mut t = cell.borrow_mut();
            assert!(
                !t.active,
                "a reverse-mode recording is already active on this thread (was a parallel task \
                 started inside a recording?)"
            );
            t.active = true;
            t.entries.clear();
            t.lattices.clear();
            drop(t);
            ACTIVE.set(cell.as_ptr());
        });
        Self {
            _thread: std::marker::PhantomData,
        }
    }

    /// Whether a recording is active on this thread.
    pub fn is_active() -> bool {
        TAPE.with(|t| t.borrow().active)
    }

    /// The current end of this thread's tape.
    pub fn mark() -> Mark {
        with_tape(|t| Mark {
            entries: t.entries.len(),
            lattices: t.lattices.len(),
        })
    }

    /// Forgets every node recorded after `mark` (values computed since then become invalid).
    pub fn rewind(mark: Mark) {
        with_tape(|t| {
            t.entries.truncate(mark.entries);
            t.lattices.truncate(mark.lattices);
        });
    }

    /// Entries (operands and node headers, 8 bytes each) on this thread's tape now (for memory
    /// accounting).
    pub fn len() -> usize {
        TAPE.with(|t| t.borrow().entries.len())
    }

    /// The gradient of `root`: calls `out(entry, ∂root/∂parameter)` for every parameter operand reached
    /// (an entry may be reported several times; the caller sums), sweeping this thread's tape backwards
    /// once. Nodes whose adjoint is zero are skipped, so an infinite partial behind a zero adjoint gives
    /// no NaN.
    pub fn sweep(root: Rev, mut out: impl FnMut(u32, f32)) {
        if root.i == CONSTANT {
            return;
        }
        if root.i & PARAM != 0 {
            out(root.i & !PARAM, 1.0);
            return;
        }
        // `out` is the caller's code: while it may run, operations go through the borrowed
        // `RefCell` (and are refused), never through `ACTIVE`.
        let active = ACTIVE.replace(std::ptr::null_mut());
        TAPE.with(|t| {
            let t = &mut *t.borrow_mut();
            let Tape {
                entries, lattices, ..
            } = t;
            let n = root.i as usize + 1;
            // The lattice records of nodes up to the root, in node order, as the nodes are.
            let reached = lattices.partition_point(|r| (r.node as usize) < n);
            let lattices = &mut lattices[..reached];
            let mut pending = reached;
            entries[n - 1].1 = 1.0;
            // Nodes in reverse order, each node's operands in the order recorded; every header up to
            // the root is visited and its adjoint taken, so all are 0 again after the sweep.
            let mut end = n;
            while end > 0 {
                let header = end - 1;
                let start = header - entries[header].0 as usize;
                let a = std::mem::take(&mut entries[header].1);
                while pending > 0 && lattices[pending - 1].node as usize == header {
                    pending -= 1;
                    lattices[pending].adjoint = a;
                }
                if a != 0.0 {
                    for k in start..header {
                        let (target, partial) = entries[k];
                        let d = a * partial;
                        if target & PARAM != 0 {
                            out(target & !PARAM, d);
                        } else {
                            entries[target as usize].1 += d;
                        }
                    }
                }
                end = start;
            }
            expand_lattices(lattices, &mut out);
        });
        ACTIVE.set(active);
    }
}

/// The block shares of the lattice records whose node the sweep reached, now that their adjoints are
/// final: consecutive records over the same taps (the value and gradient sums of one lookup) are summed
/// into one 4×4×4 array first, so each value of a lookup is reported once. Records with a zero adjoint
/// are skipped, as nodes are.
fn expand_lattices(lattices: &[LatticeRecord], out: &mut impl FnMut(u32, f32)) {
    let mut shares = [[[0.0f32; 4]; 4]; 4];
    let mut pending: Option<&LatticeRecord> = None;
    let flush =
        |r: &LatticeRecord, shares: &mut [[[f32; 4]; 4]; 4], out: &mut dyn FnMut(u32, f32)| {
            let [ix, iy, iz] = r.index;
            for (c, plane) in shares.iter_mut().enumerate() {
                for (b, row) in plane.iter_mut().enumerate() {
                    let start = r.first + (iz[c] * r.ny + iy[b]) * r.nx;
                    for (a, share) in row.iter_mut().enumerate() {
                        out(start + ix[a], std::mem::take(share));
                    }
                }
            }
        };
    for r in lattices {
        let a = r.adjoint;
        if a == 0.0 {
            continue;
        }
        if let Some(p) = pending.filter(|p| !p.same_taps(r)) {
            flush(p, &mut shares, out);
        }
        pending = Some(r);
        let [wx, wy, wz] = r.weight;
        for (plane, &z) in shares.iter_mut().zip(&wz) {
            for (row, &y) in plane.iter_mut().zip(&wy) {
                let azy = a * z * y;
                for (share, &x) in row.iter_mut().zip(&wx) {
                    *share += azy * x;
                }
            }
        }
    }
    if let Some(p) = pending {
        flush(p, &mut shares, out);
    }
}

impl Drop for Recording {
    fn drop(&mut self) {
        ACTIVE.set(std::ptr::null_mut());
        TAPE.with(|t| {
            let mut t = t.borrow_mut();
            t.active = false;
            t.entries.clear();
            t.lattices.clear();
        });
    }
}

impl Add for Rev {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.binary(o, (self.v + o.v, 1.0, 1.0))
    }
}

impl Sub for Rev {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.binary(o, (self.v - o.v, 1.0, -1.0))
    }
}

impl Mul for Rev {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.binary(o, rules::mul(self.v, o.v))
    }
}

impl Div for Rev {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.binary(o, rules::div(self.v, o.v))
    }
}

impl Neg for Rev {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.unary((-self.v, -1.0))
    }
}

// Mixed operations with a constant `f32`, with the primal arithmetic of `DualN`'s.
impl Add<f32> for Rev {
    type Output = Self;
    #[inline(always)]
    fn add(self, c: f32) -> Self {
        self.unary((self.v + c, 1.0))
    }
}

impl Sub<f32> for Rev {
    type Output = Self;
    #[inline(always)]
    fn sub(self, c: f32) -> Self {
        self.unary((self.v - c, 1.0))
    }
}

impl Mul<f32> for Rev {
    type Output = Self;
    #[inline(always)]
    fn mul(self, c: f32) -> Self {
        self.unary((self.v * c, c))
    }
}

impl Div<f32> for Rev {
    type Output = Self;
    #[inline(always)]
    fn div(self, c: f32) -> Self {
        self.unary((self.v / c, 1.0 / c))
    }
}

macro_rules! assign_ops {
    ($($tr:ident $m:ident $op:tt),*) => {$(
        impl $tr for Rev {
            #[inline(always)]
            fn $m(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    )*};
}
assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl Scalar for Rev {
    const FIRST_ORDER: bool = true;
    const RECORDED: bool = true;
    /// One node whose operands are the terms.
    #[inline(always)]
    fn affine(value: f32, terms: &[(Self, f32)]) -> Self {
        Self::record(value, terms)
    }
    #[inline(always)]
    fn constant(v: f32) -> Self {
        Self::new(v)
    }
    #[inline(always)]
    fn is_constant(self) -> bool {
        Rev::is_constant(self)
    }
    #[inline(always)]
    fn primal(self) -> f32 {
        self.v
    }
    /// Slot `k` is gradient entry `k`; `None` is a constant.
    #[inline(always)]
    fn lift(value: f32, slot: Slot) -> Self {
        match slot {
            Some(k) => Self::parameter(value, k),
            None => Self::new(value),
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.unary(rules::sqrt(self.v))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        self.unary(rules::exp(self.v))
    }
    #[inline(always)]
    fn ln(self) -> Self {
        self.unary(rules::ln(self.v))
    }
    #[inline(always)]
    fn sin(self) -> Self {
        self.unary(rules::sin(self.v))
    }
    #[inline(always)]
    fn cos(self) -> Self {
        self.unary(rules::cos(self.v))
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        self.binary(x, rules::atan2(self.v, x.v))
    }
    #[inline(always)]
    fn acos(self) -> Self {
        self.unary(rules::acos(self.v))
    }
    #[inline(always)]
    fn powf(self, n: f32) -> Self {
        self.unary(rules::powf(self.v, n))
    }
    #[inline(always)]
    fn recip(self) -> Self {
        self.unary(rules::recip(self.v))
    }
    #[inline(always)]
    fn sqr(self) -> Self {
        self.unary(rules::sqr(self.v))
    }

    /// Four lattice nodes (no operands: the weights are constants), the sums computed in one pass
    /// unless given; the gradient's primals are those of the generic path, which adds two constant
    /// zero parts to each.
    fn lattice_sum_with_gradient(
        taps: &LatticeTaps<f32>,
        deriv: &[[f32; 4]; 3],
        values: &[f32],
        dims: [usize; 3],
        block: Slot,
        sums: Option<[f32; 4]>,
    ) -> Option<[Self; 4]> {
        let first = block?;
        let [nx, ny, _] = dims;
        let [v, px, py, pz] = match sums {
            Some(sums) => sums,
            None => lattice_sums_with_derivatives_f32(taps, deriv, values, nx, ny)?,
        };
        let [wx, wy, wz] = taps.weight;
        let [dx, dy, dz] = *deriv;
        let lattice = (dims, values.len());
        with_tape(|t| {
            let mut node = |v: f32, weight: [[f32; 4]; 3]| {
                let i = t.node(t.entries.len());
                t.lattices
                    .push(LatticeRecord::new(i, first, lattice, taps.index, weight));
                Self { v, i }
            };
            Some([
                node(v, [wx, wy, wz]),
                node((px + 0.0) + 0.0, [dx, wy, wz]),
                node((0.0 + py) + 0.0, [wx, dy, wz]),
                node((0.0 + 0.0) + pz, [wx, wy, dz]),
            ])
        })
    }

    /// One node of primal 0 whose operands are the block's entries with the weights as partials.
    fn block_terms(first: u32, terms: &[(usize, f32)]) -> Self {
        if terms.is_empty() {
            return Self::new(0.0);
        }
        with_tape(|t| {
            let start = t.entries.len();
            for &(i, w) in terms {
                let entry = first as usize + i;
                debug_assert!(entry <= MAX_GRADIENT_ENTRY as usize);
                t.operand(PARAM | entry as u32, w);
            }
            let i = t.node(start);
            Self { v: 0.0, i }
        })
    }

    /// One node: the primal is the nested `f32` sum (bit for bit the image's); its operands are every
    /// non-constant weight (partial: the sum over the other two axes) and, as one [`LatticeRecord`]
    /// expanded after the sweep, the 64 values of block `block` (partial: the product of the three
    /// weights). An axis whose weights are all constant zeros (a spatial derivative along another
    /// axis) gives a constant 0 without recording.
    fn lattice_sum(
        taps: &LatticeTaps<Self>,
        values: &[f32],
        dims: [usize; 3],
        block: Slot,
    ) -> Self {
        let [nx, ny, _] = dims;
        if taps
            .weight
            .iter()
            .any(|axis| axis.iter().all(|w| w.i == CONSTANT && w.v == 0.0))
        {
            return Self::new(0.0);
        }
        let primal = taps.map(|_, w| w.v);
        let v = lattice_sum_f32(&primal, values, nx, ny);
        let moving = taps.weight.iter().flatten().any(|w| w.i != CONSTANT);
        if block.is_none() && !moving {
            return Self::new(v);
        }
        let [ix, iy, iz] = taps.index;
        let [wx, wy, wz] = primal.weight;
        with_tape(|t| {
            let start = t.entries.len();
            if moving {
                // ∂/∂w_axis[k]: the sum with that axis's weights replaced by the unit vector e_k,
                // i.e. the values contracted with the other two axes' weights.
                let mut d = [[0.0f32; 4]; 3];
                for c in 0..4 {
                    for b in 0..4 {
                        let row = (iz[c] * ny + iy[b]) * nx;
                        let v = [0, 1, 2, 3].map(|a| values[row + ix[a]]);
                        let along_x = wx[0] * v[0] + wx[1] * v[1] + wx[2] * v[2] + wx[3] * v[3];
                        for a in 0..4 {
                            d[0][a] += wz[c] * wy[b] * v[a];
                        }
                        d[1][b] += wz[c] * along_x;
                        d[2][c] += wy[b] * along_x;
                    }
                }
                for (weights, partials) in taps.weight.iter().zip(&d) {
                    for (w, &p) in weights.iter().zip(partials) {
                        if w.i != CONSTANT {
                            t.operand(w.i, p);
                        }
                    }
                }
            }
            let i = t.node(start);
            if let Some(first) = block {
                t.lattices.push(LatticeRecord::new(
                    i,
                    first,
                    (dims, values.len()),
                    taps.index,
                    primal.weight,
                ));
            }
            Self { v, i }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{DualN, lattice_sum_nested};

    /// A 5×4×6 lattice of distinct values.
    fn lattice() -> (Vec<f32>, [usize; 3]) {
        let dims = [5, 4, 6];
        let values = (0..5 * 4 * 6)
            .map(|i| ((i * 37 % 23) as f32 - 11.0) * 0.1)
            .collect();
        (values, dims)
    }

    /// The weights of one point, the x weights as parameters 0..4 (entries past the block's end).
    fn taps<S: Scalar>(seed: impl Fn(f32, u32) -> S) -> LatticeTaps<S> {
        LatticeTaps {
            index: [[0, 1, 2, 4], [0, 1, 2, 3], [1, 2, 3, 5]],
            weight: [
                std::array::from_fn(|a| seed([0.1, 0.5, 0.3, 0.1][a], 1000 + a as u32)),
                [0.2, 0.4, 0.3, 0.1].map(S::constant),
                [0.25, 0.25, 0.4, 0.1].map(S::constant),
            ],
        }
    }

    /// One node over a block and moving weights: the primal is `f32`'s bit for bit, each value's partial
    /// is its weight product, and each weight's partial agrees with forward mode seeded in it.
    #[test]
    fn lattice_sum_partials_match_forward_mode() {
        let (values, dims) = lattice();
        let _recording = Recording::start();
        let rev = Rev::lattice_sum(&taps(Rev::parameter), &values, dims, Some(0));
        let plain = lattice_sum_nested(&taps(|w, _| w), &values, dims[0], dims[1]);
        assert_eq!(rev.primal().to_bits(), plain.to_bits());
        let mut grad = vec![0.0f32; 1004];
        Recording::sweep(rev, |e, d| grad[e as usize] += d);
        let t = taps(|w, _| w);
        for (c, &z) in t.index[2].iter().enumerate() {
            for (b, &y) in t.index[1].iter().enumerate() {
                for (a, &x) in t.index[0].iter().enumerate() {
                    let e = (z * dims[1] + y) * dims[0] + x;
                    let w = t.weight[2][c] * t.weight[1][b] * t.weight[0][a];
                    // Every index of this point is distinct, so each entry is one product.
                    assert!((grad[e] - w).abs() <= 1e-6, "value {e}: {} vs {w}", grad[e]);
                }
            }
        }
        let dual = lattice_sum_nested(
            &taps(|w, k| DualN::<4>::variable(w, (k - 1000) as usize)),
            &values,
            dims[0],
            dims[1],
        );
        for k in 0..4 {
            let (r, f) = (grad[1000 + k], dual.eps[k]);
            assert!(
                (r - f).abs() <= 1e-5 * f.abs().max(1.0),
                "weight {k}: {r} vs {f}"
            );
        }
    }

    /// A lookup at a point seeded in space only (constant weights, each axis's derivative along its own
    /// axis) takes the one-pass path: four nodes, the primals bit for bit those of the generic sums
    /// (each a sum with one axis's weights replaced by their derivatives, plus two zero parts), and
    /// each value's share of each sum its weight product.
    #[test]
    fn a_spatially_seeded_lookup_is_four_nodes_with_the_generic_sums() {
        use crate::scalar::Grad;
        let (values, dims) = lattice();
        let fixed = LatticeTaps {
            index: [[1, 2, 3, 4], [0, 1, 2, 3], [1, 2, 3, 5]],
            weight: [
                [0.1, 0.5, 0.3, 0.1],
                [0.2, 0.4, 0.3, 0.1],
                [0.25, 0.25, 0.4, 0.1],
            ],
        };
        let deriv = [
            [-0.5, -0.7, 0.9, 0.3],
            [-0.2, 0.6, -0.1, -0.3],
            [0.45, -1.0, 0.05, 0.5],
        ];
        let taps = LatticeTaps {
            index: fixed.index,
            weight: std::array::from_fn(|a| {
                std::array::from_fn(|k| {
                    let mut g = [Rev::new(0.0); 3];
                    g[a] = Rev::new(deriv[a][k]);
                    Grad {
                        v: Rev::new(fixed.weight[a][k]),
                        g,
                    }
                })
            }),
        };
        let _recording = Recording::start();
        let r = Grad::<Rev>::lattice_sum(&taps, &values, dims, Some(0));
        assert_eq!(Recording::len(), 4, "one header per sum, no other node");
        let replaced = |axis: usize| {
            let mut t = fixed;
            t.weight[axis] = deriv[axis];
            lattice_sum_f32(&t, &values, dims[0], dims[1])
        };
        let expected = [
            lattice_sum_f32(&fixed, &values, dims[0], dims[1]),
            (replaced(0) + 0.0) + 0.0,
            (0.0 + replaced(1)) + 0.0,
            (0.0 + 0.0) + replaced(2),
        ];
        let outputs = [r.v, r.g[0], r.g[1], r.g[2]];
        for (k, (out, e)) in outputs.iter().zip(expected).enumerate() {
            assert_eq!(out.primal().to_bits(), e.to_bits(), "sum {k}");
            let mut grad = vec![0.0f32; values.len()];
            Recording::sweep(*out, |e, d| grad[e as usize] += d);
            let mut w = fixed.weight;
            if k > 0 {
                w[k - 1] = deriv[k - 1];
            }
            for (c, &z) in fixed.index[2].iter().enumerate() {
                for (b, &y) in fixed.index[1].iter().enumerate() {
                    for (a, &x) in fixed.index[0].iter().enumerate() {
                        let e = (z * dims[1] + y) * dims[0] + x;
                        let p = w[2][c] * w[1][b] * w[0][a];
                        assert!(
                            (grad[e] - p).abs() <= 1e-6,
                            "sum {k}, value {e}: {} vs {p}",
                            grad[e]
                        );
                    }
                }
            }
        }
    }

    /// The sweep's callback is the caller's code: an operation recorded from it is refused (the tape
    /// is borrowed), never written through the recording's fast path under the sweep's feet.
    #[test]
    #[should_panic(expected = "already borrowed")]
    fn an_operation_inside_the_sweep_callback_is_refused() {
        let _recording = Recording::start();
        let x = Rev::parameter(2.0, 0);
        let y = x * x;
        Recording::sweep(y, |_, d| {
            let _ = Rev::parameter(d, 1) * x;
        });
    }

    /// A sweep leaves the tape as it found it: sweeping the same root twice, or an earlier node after a
    /// later one, gives each its own gradient (the adjoints accumulated in the nodes are cleared).
    #[test]
    fn sweeps_of_one_recording_are_independent() {
        let _recording = Recording::start();
        let x = Rev::parameter(3.0, 0);
        let y = x * x;
        let z = y * x + x;
        let grad = |root: Rev| {
            let mut g = 0.0;
            Recording::sweep(root, |_, d| g += d);
            g
        };
        assert_eq!(grad(z), 28.0);
        assert_eq!(grad(z), 28.0);
        assert_eq!(grad(y), 6.0);
        assert_eq!(grad(z), 28.0);
    }

    /// Samples recorded one after another on one recording, rewound in between, each get their own
    /// gradient (the fast path is restored after a sweep).
    #[test]
    fn rewound_samples_get_their_own_gradients() {
        let _recording = Recording::start();
        for k in 1..4 {
            let mark = Recording::mark();
            let x = Rev::parameter(k as f32, 0);
            let y = x * x * x + x * 2.0;
            let mut g = 0.0;
            Recording::sweep(y, |e, d| {
                assert_eq!(e, 0);
                g += d;
            });
            assert_eq!(g, 3.0 * (k * k) as f32 + 2.0);
            Recording::rewind(mark);
            assert_eq!(Recording::len(), 0);
        }
    }

    #[test]
    #[should_panic(expected = "already active")]
    fn a_second_recording_on_the_same_thread_is_refused() {
        let _a = Recording::start();
        let _b = Recording::start();
    }
}
