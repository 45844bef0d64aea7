//! Identical, uncoupled chains of the reaction matrix factored side by side.
//!
//! A structure with an n-fold symmetry (the paper's tower: three chains of joints, one per
//! strut of a stage) has a reaction matrix made of identical parts with no block between
//! them. Here each entry of up to [`LANES`] such parts is one `[f64; LANES]`, so every
//! operation of the factorization and the solves works on all of them at once, in SIMD
//! registers: AVX2 when the processor has it, two SSE2 halves otherwise. Lane by lane the
//! arithmetic is the scalar factor's, operation for operation and without fused
//! multiply-adds, so the results are the same bits on any x86-64.

use nalgebra::Matrix3;

use super::pattern::{components, Pattern};
use super::symmetric::{summed, Symmetric};

/// Parts per group.
pub(crate) const LANES: usize = 4;

/// The most memory the lanes' K and factor may take. Beyond it (about 4,000 tower bars)
/// the 4-wide arrays stream from L3 or memory and cost more than the lanes save (`bench`,
/// tower vs the scalar factor: 0.93× the time per step at 2,100 bars, 1.04× at 6,000,
/// 1.27× at 60,000, measured when the lanes gathered a copy of the scalar K), so larger
/// systems keep the scalar factor.
const MAX_BYTES: usize = 2 << 20;
/// One value per lane, aligned to 32 bytes so that no lane-wise load or store straddles two
/// cache lines (unaligned, every other entry of a block did, and a store to one did not
/// pass its value on to the next load of it).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Lanes(pub [f64; LANES]);

impl std::ops::Deref for Lanes {
    type Target = [f64; LANES];
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl std::ops::DerefMut for Lanes {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

/// All lanes zero.
const ZERO: Lanes = Lanes([0.0; LANES]);
/// One 3 × 3 block per lane, entry (i, j) at `3 j + i` (nalgebra's order).
pub(crate) type Block = [Lanes; 9];

/// K's parts in groups of identical ones. K is assembled straight into the groups'
/// layout (no gather before each factor).
#[derive(Debug, Clone)]
pub struct LaneGroups {
    groups: Vec<LaneGroup>,
    /// The groups' blocks of K, group after group; the factor overwrites them (pivot
    /// blocks included: here the lanes' stores are not the bottleneck).
    k: Vec<Block>,
    /// Per slot of the scalar layout, its block in `k` times [`LANES`], plus its lane.
    lane_of: Vec<usize>,
}

/// Up to [`LANES`] identical parts; lane `l` is part `l`. Unused lanes hold identity pivots
/// and zero blocks, which the factor keeps; their pivots are not tested (an identity pivot
/// would fail the test once K's scale reaches 1e12).
#[derive(Debug, Clone)]
struct LaneGroup {
    /// The parts' common pattern, in a part's own column numbering.
    pattern: Pattern,
    /// Per local column, the original column of each used lane.
    columns: Vec<[usize; LANES]>,
    /// Where the group's blocks start in [`LaneGroups::k`].
    k_start: usize,
    used: usize,
    l: Vec<Block>,
    d_inv: Vec<Block>,
    rhs: Vec<[Lanes; 3]>,
}

impl LaneGroups {
    /// Groups the connected components of K (its factor's `scalar` pattern, of
    /// `lower_blocks`) by their pattern, if K is made of at least two components and each has
    /// at least one twin (else the scalar factor is as good).
    pub fn find(scalar: &Pattern, lower_blocks: &[(usize, usize)]) -> Option<Self> {
        let n = scalar.columns();
        let components = components(n, lower_blocks);
        if components.len() < 2 {
            return None;
        }
        let mut local = vec![0; n];
        let mut component_of = vec![0; n];
        for (i, columns) in components.iter().enumerate() {
            for (k, &c) in columns.iter().enumerate() {
                local[c] = k;
                component_of[c] = i;
            }
        }
        let mut shapes: Vec<Vec<(usize, usize)>> = vec![Vec::new(); components.len()];
        // Off-diagonal blocks only: every column has its diagonal block.
        for &(r, c) in lower_blocks.iter().filter(|(r, c)| r != c) {
            shapes[component_of[c]].push((local[r], local[c]));
        }
        for shape in &mut shapes {
            shape.sort_unstable();
            shape.dedup();
        }
        // Components of one shape (same size, same blocks), in order of their first column.
        let mut classes: Vec<Vec<usize>> = Vec::new();
        for i in 0..components.len() {
            let twin = |class: &&mut Vec<usize>| {
                let j = class[0];
                components[j].len() == components[i].len() && shapes[j] == shapes[i]
            };
            match classes.iter_mut().find(twin) {
                Some(class) => class.push(i),
                None => classes.push(vec![i]),
            }
        }
        if classes.iter().any(|class| class.len() < 2) {
            return None;
        }
        // One symbolic factor per class; the memory checked before any lane is allocated.
        let patterns: Vec<Pattern> = classes
            .iter()
            .map(|class| Pattern::new(components[class[0]].len(), &shapes[class[0]]))
            .collect();
        let bytes: usize = classes
            .iter()
            .zip(&patterns)
            .map(|(class, pattern)| class.len().div_ceil(LANES) * LaneGroup::bytes(pattern))
            .sum();
        if bytes > MAX_BYTES {
            return None;
        }
        let mut lanes = Self {
            groups: Vec::new(),
            k: Vec::new(),
            lane_of: vec![usize::MAX; scalar.slots()],
        };
        for (class, pattern) in classes.iter().zip(&patterns) {
            for members in class.chunks(LANES) {
                let parts: Vec<&[usize]> = members.iter().map(|&i| &components[i][..]).collect();
                lanes.add_group(scalar, &parts, pattern.clone())?;
            }
        }
        // Every component is in a group, and its fill is its share of K's: every slot has
        // its place in the lanes.
        debug_assert!(!lanes.lane_of.contains(&usize::MAX));
        Some(lanes)
    }

    /// Adds a group of `parts` (each its original columns, in order) of the common
    /// `pattern`, K's slots found in its `scalar` pattern.
    fn add_group(&mut self, scalar: &Pattern, parts: &[&[usize]], pattern: Pattern) -> Option<()> {
        let m = parts[0].len();
        let k_start = self.k.len();
        let mut columns = vec![[0; LANES]; m];
        for (lane, part) in parts.iter().enumerate() {
            for c in 0..m {
                columns[c][lane] = part[c];
                for p in pattern.l_start[c]..pattern.l_start[c + 1] {
                    // Fill is the same as in K's own factor: a part keeps its columns' order.
                    let slot = scalar.slot(part[pattern.l_rows[p]], part[c])?;
                    self.lane_of[slot] = (k_start + p) * LANES + lane;
                }
            }
        }
        // Unused lanes: identity pivots and zero blocks (updates subtract zero products).
        let slots = pattern.l_rows.len();
        self.k.resize(k_start + slots, [ZERO; 9]);
        for c in 0..m {
            for e in [0, 4, 8] {
                self.k[k_start + pattern.l_start[c]][e][parts.len()..].fill(1.0);
            }
        }
        self.groups.push(LaneGroup {
            columns,
            k_start,
            used: parts.len(),
            l: vec![[ZERO; 9]; slots],
            d_inv: vec![[ZERO; 9]; m],
            rhs: vec![[ZERO; 3]; m],
            pattern,
        });
        Some(())
    }

    /// Sets K's block at `slot` of the scalar layout.
    pub fn set(&mut self, slot: usize, block: &Matrix3<f64>) {
        let (at, lane) = self.entries(slot);
        for (e, &x) in block.as_slice().iter().enumerate() {
            at[e][lane] = x;
        }
    }

    /// Sets (`first`) or adds to K's symmetric block at `slot` of the scalar layout, given
    /// by its lower triangle.
    #[inline(always)]
    pub fn put_symmetric(&mut self, slot: usize, lower: &Symmetric, first: bool) {
        let (at, lane) = self.entries(slot);
        for (e, x) in summed(lower, first, |e| at[e][lane])
            .into_iter()
            .enumerate()
        {
            at[e][lane] = x;
        }
    }

    /// Where K's block at `slot` of the scalar layout lies: its block of the lanes and its
    /// lane.
    pub(crate) fn position(&self, slot: usize) -> (usize, usize) {
        let at = self.lane_of[slot];
        (at / LANES, at % LANES)
    }

    /// How many lanes of the lanes' block `block` hold a part (the others hold only 0 and
    /// the 1 of identity pivots, before and after a factor).
    pub(crate) fn used_lanes(&self, block: usize) -> usize {
        let group = self
            .groups
            .iter()
            .find(|g| (g.k_start..g.k_start + g.l.len()).contains(&block));
        group.expect("a block of some group").used
    }

    /// The lanes' block `block` of K, to assemble into (by the AVX2 bundles).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(crate) fn block_mut(&mut self, block: usize) -> &mut Block {
        &mut self.k[block]
    }

    /// Every lane of K's blocks, unused lanes included, as bits.
    #[cfg(test)]
    pub(crate) fn k_bits(&self) -> Vec<u64> {
        let entries = self.k.iter().flatten().flat_map(|lanes| lanes.0);
        entries.map(f64::to_bits).collect()
    }

    /// The block of `slot` and its lane (masked, so that indexing needs no check).
    #[inline(always)]
    fn entries(&mut self, slot: usize) -> (&mut Block, usize) {
        let at = self.lane_of[slot];
        (&mut self.k[at / LANES], at % LANES)
    }

    /// K's block at `slot` of the scalar layout, as last set (the factor overwrites it).
    pub fn block(&self, slot: usize) -> Matrix3<f64> {
        let at = self.lane_of[slot];
        let (block, lane) = (&self.k[at / LANES], at % LANES);
        Matrix3::from_fn(|i, j| block[3 * j + i][lane])
    }

    /// The largest magnitude on K's diagonal blocks' diagonals (NaNs skipped, as
    /// `f64::max` does).
    #[inline(always)]
    fn diagonal_amax(&self) -> f64 {
        let mut scale: f64 = 0.0;
        for group in &self.groups {
            let mut lane_max = ZERO;
            let pattern = &group.pattern;
            for &d in &pattern.l_start[..group.columns.len()] {
                let block = &self.k[group.k_start + d];
                for e in [0, 4, 8] {
                    lane_max = lanes(|l| lane_max[l].max(block[e][l].abs()));
                }
            }
            scale = lane_max[..group.used]
                .iter()
                .fold(scale, |m, &x| f64::max(m, x));
        }
        scale
    }

    /// Factors K as assembled and solves `K x = b` in place (`b` by original column);
    /// false if a pivot of any part fails (`b` is then overwritten too).
    pub fn factor_and_solve(&mut self, singular: f64, b: &mut [[f64; 3]]) -> bool {
        crate::simd::dispatch!(LaneGroups::factor_and_solve_lanes(
            groups: &mut LaneGroups = self,
            singular: f64,
            b: &mut [[f64; 3]],
        ) -> bool)
    }

    /// [`Self::factor_and_solve`] compiled for baseline x86-64 only (SSE2), as on a
    /// processor without AVX2.
    #[cfg(test)]
    pub fn factor_and_solve_portable(&mut self, singular: f64, b: &mut [[f64; 3]]) -> bool {
        self.factor_and_solve_lanes(singular, b)
    }

    /// The factor with pivots tested against `singular` times K's largest diagonal entry,
    /// and the solve.
    #[inline(always)]
    fn factor_and_solve_lanes(&mut self, singular: f64, b: &mut [[f64; 3]]) -> bool {
        let tiny = singular * self.diagonal_amax();
        // A plain loop: `Iterator::all` was compiled out of line, outside the AVX2 caller.
        for group in &mut self.groups {
            let k = &mut self.k[group.k_start..group.k_start + group.l.len()];
            if !group.factor_and_solve(k, tiny, b) {
                return false;
            }
        }
        true
    }
}

impl LaneGroup {
    /// Memory of a group's factor and right-hand side (`k`, `l`, `d_inv`, `rhs`) for its
    /// parts' pattern.
    fn bytes(pattern: &Pattern) -> usize {
        use std::mem::size_of;
        let (slots, columns) = (pattern.l_rows.len(), pattern.l_start.len() - 1);
        (2 * slots + columns) * size_of::<Block>() + columns * size_of::<[Lanes; 3]>()
    }

    /// The group's factor and solve: its parts' right-hand sides gathered into lanes, the
    /// forward substitution inside the factor's sweep (as in the scalar factor), the
    /// backward one, and the solution scattered back.
    #[inline(always)]
    fn factor_and_solve(&mut self, k: &mut [Block], tiny: f64, b: &mut [[f64; 3]]) -> bool {
        for (x, columns) in self.rhs.iter_mut().zip(&self.columns) {
            for (lane, &c) in columns.iter().enumerate().take(self.used) {
                for i in 0..3 {
                    x[i][lane] = b[c][i];
                }
            }
        }
        let (pattern, rhs) = (&self.pattern, &mut self.rhs);
        for c in 0..self.columns.len() {
            let diagonal = pattern.l_start[c];
            for u in &pattern.updates[pattern.update_start[c]..pattern.update_start[c + 1]] {
                // `with` is in an earlier column than `target`, so in an earlier slot.
                let (earlier, from_target) = k.split_at_mut(u.target);
                let lower = u.target == diagonal;
                subtract_abt(
                    &mut from_target[0],
                    &self.l[u.source],
                    &earlier[u.with],
                    lower,
                );
            }
            let d_inv = &mut self.d_inv[c];
            if !inverse3(&k[diagonal], tiny, self.used, d_inv) {
                return false;
            }
            let y = rhs[c];
            // Indexed: zipping the two slices took 0.4% more instructions (callgrind).
            #[allow(clippy::needless_range_loop)]
            for p in diagonal + 1..pattern.l_start[c + 1] {
                mul_symmetric(&k[p], d_inv, &mut self.l[p]);
                let ly = mul_vector(&self.l[p], &y);
                let bi = &mut rhs[pattern.l_rows[p]];
                for i in 0..3 {
                    bi[i] = lanes(|l| bi[i][l] - ly[i][l]);
                }
            }
        }
        for k in (0..rhs.len()).rev() {
            let mut x = mul_vector(&self.d_inv[k], &rhs[k]);
            for p in pattern.l_start[k] + 1..pattern.l_start[k + 1] {
                let t = tr_mul_vector(&self.l[p], &rhs[pattern.l_rows[p]]);
                for j in 0..3 {
                    x[j] = lanes(|l| x[j][l] - t[j][l]);
                }
            }
            rhs[k] = x;
        }
        for (x, columns) in self.rhs.iter().zip(&self.columns) {
            for (lane, &c) in columns.iter().enumerate().take(self.used) {
                for i in 0..3 {
                    b[c][i] = x[i][lane];
                }
            }
        }
        true
    }
}

/// A lane-wise value.
#[inline(always)]
pub(crate) fn lanes(f: impl Fn(usize) -> f64) -> Lanes {
    Lanes(std::array::from_fn(f))
}

/// `s −= a bᵀ` (only the lower triangle for a pivot), each entry as the scalar kernel sums it.
#[inline(always)]
fn subtract_abt(s: &mut Block, a: &Block, b: &Block, lower: bool) {
    for j in 0..3 {
        for i in if lower { j } else { 0 }..3 {
            let (a0, a1, a2) = (&a[i], &a[3 + i], &a[6 + i]);
            let (b0, b1, b2) = (&b[j], &b[3 + j], &b[6 + j]);
            let s = &mut s[3 * j + i];
            *s = lanes(|l| s[l] - (a0[l] * b0[l] + a1[l] * b1[l] + a2[l] * b2[l]));
        }
    }
}

/// `out = a d` for a symmetric `d`.
#[inline(always)]
fn mul_symmetric(a: &Block, d: &Block, out: &mut Block) {
    for j in 0..3 {
        for i in 0..3 {
            let (a0, a1, a2) = (&a[i], &a[3 + i], &a[6 + i]);
            let (d0, d1, d2) = (&d[3 * j], &d[3 * j + 1], &d[3 * j + 2]);
            out[3 * j + i] = lanes(|l| a0[l] * d0[l] + a1[l] * d1[l] + a2[l] * d2[l]);
        }
    }
}

/// `a x`, summed column by column as nalgebra's matrix–vector product does.
#[inline(always)]
fn mul_vector(a: &Block, x: &[Lanes; 3]) -> [Lanes; 3] {
    std::array::from_fn(|i| {
        lanes(|l| a[i][l] * x[0][l] + a[3 + i][l] * x[1][l] + a[6 + i][l] * x[2][l])
    })
}

/// `aᵀ x`, each entry a dot product as nalgebra's `tr_mul` sums it.
#[inline(always)]
fn tr_mul_vector(a: &Block, x: &[Lanes; 3]) -> [Lanes; 3] {
    std::array::from_fn(|j| {
        lanes(|l| a[3 * j][l] * x[0][l] + a[3 * j + 1][l] * x[1][l] + a[3 * j + 2][l] * x[2][l])
    })
}

/// The scalar `inverse3` lane by lane, into `inv`; false if a pivot of one of the first
/// `used` lanes fails its test.
#[inline(always)]
fn inverse3(a: &Block, tiny: f64, used: usize, inv: &mut Block) -> bool {
    let (a00, a10, a20, a11, a21, a22) = (a[0], a[1], a[2], a[4], a[5], a[8]);
    let c00 = lanes(|l| a11[l] * a22[l] - a21[l] * a21[l]);
    let c10 = lanes(|l| a20[l] * a21[l] - a10[l] * a22[l]);
    let c20 = lanes(|l| a10[l] * a21[l] - a11[l] * a20[l]);
    let m2 = lanes(|l| a00[l] * a11[l] - a10[l] * a10[l]);
    let det = lanes(|l| a00[l] * c00[l] + a10[l] * c10[l] + a20[l] * c20[l]);
    let pivots_pass = (0..used)
        .map(|l| a00[l] > tiny && m2[l] > tiny * a00[l] && det[l] > tiny * m2[l])
        .fold(true, |all, ok| all & ok);
    if !pivots_pass {
        return false;
    }
    let r = lanes(|l| 1.0 / det[l]);
    let c11 = lanes(|l| a00[l] * a22[l] - a20[l] * a20[l]);
    let c21 = lanes(|l| a10[l] * a20[l] - a00[l] * a21[l]);
    let scaled = |c: Lanes| lanes(|l| c[l] * r[l]);
    *inv = [
        scaled(c00),
        scaled(c10),
        scaled(c20),
        scaled(c10),
        scaled(c11),
        scaled(c21),
        scaled(c20),
        scaled(c21),
        scaled(m2),
    ];
    true
}
