//! The tests of [`super`].

use super::*;
use nalgebra::{DMatrix, Vector3};

/// K with random blocks on `pattern` and random SPD diagonal blocks, and a random
/// right-hand side.
fn random_spd(n: usize, pattern: &[(usize, usize)], seed: u64) -> (BlockLdl, DVector<f64>) {
    let mut seed = seed;
    let mut rand = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut chol = BlockLdl::new(n, pattern);
    for &(r, c) in pattern {
        let idx = chol.k_index(r, c).unwrap();
        chol.set(idx, &Matrix3::from_fn(|_, _| rand()));
    }
    for k in 0..n {
        let a = Matrix3::from_fn(|_, _| rand());
        let idx = chol.k_index(k, k).unwrap();
        chol.set(idx, &(a * a.transpose() + Matrix3::identity() * 8.0));
    }
    let b = DVector::from_fn(3 * n, |_, _| rand());
    (chol, b)
}

/// A random SPD block matrix with a given block pattern agrees with a dense solve.
#[test]
fn solves_like_dense_cholesky() {
    let pattern = [
        (1, 0),
        (3, 0),
        (2, 1),
        (4, 2),
        (6, 3),
        (5, 4),
        (6, 5),
        (6, 0),
    ];
    let (mut chol, b) = random_spd(7, &pattern, 12345);
    let dense: DMatrix<f64> = chol.dense();
    let mut x = b.clone();
    assert!(chol.factor_and_solve(&mut x));
    let expected = dense.cholesky().unwrap().solve(&b);
    assert!((x - expected).amax() < 1e-12);
}

#[test]
fn singular_matrix_is_reported() {
    let mut chol = BlockLdl::new(2, &[(1, 0)]);
    let u = Vector3::new(1.0, 2.0, 2.0) / 3.0;
    let a = Matrix3::identity() * 4.0 - u * u.transpose() * 3.0;
    for (r, c, m) in [(0, 0, a), (1, 1, a), (1, 0, -a)] {
        let idx = chol.k_index(r, c).unwrap();
        chol.set(idx, &m);
    }
    assert!(!chol.factor_and_solve(&mut DVector::zeros(6)));
}

/// Three uncoupled chains with the same pattern, interleaved as the tower's are (column
/// c in chain c mod 3), each with fill, random SPD values per chain.
fn three_chains(seed: u64) -> (BlockLdl, DVector<f64>) {
    let links = 7;
    let n = 3 * links;
    let mut pattern = Vec::new();
    for chain in 0..3 {
        for k in 0..links - 1 {
            pattern.push((3 * (k + 1) + chain, 3 * k + chain));
        }
        pattern.push((3 * (links - 1) + chain, chain));
    }
    random_spd(n, &pattern, seed)
}

/// Side by side, the chains factor and solve to the scalar factor's bits, and agree
/// with a dense solve.
#[test]
fn chains_side_by_side_give_the_scalar_bits() {
    for seed in [1, 2, 3] {
        let (mut lanes, b) = three_chains(seed);
        assert!(lanes.has_lanes(), "identical chains go side by side");
        let mut scalar = lanes.clone().without_lanes();
        let dense = lanes.dense();
        let (mut x, mut y) = (b.clone(), b.clone());
        assert!(lanes.factor_and_solve(&mut x) && scalar.factor_and_solve(&mut y));
        for (p, q) in x.iter().zip(y.iter()) {
            assert_eq!(p.to_bits(), q.to_bits());
        }
        let mut portable = three_chains(seed).0;
        let mut z = b.clone();
        assert!(portable.factor_and_solve_portable(&mut z));
        assert!(x
            .iter()
            .zip(z.iter())
            .all(|(p, q)| p.to_bits() == q.to_bits()));
        let expected = dense.cholesky().unwrap().solve(&b);
        assert!((x - expected).amax() < 1e-12);
    }
}

/// At a large scale (tiny ≥ 1: light bars make K's entries ~1/m) the unused lane's
/// identity pivots must not fail the factor: side by side it succeeds as the scalar one
/// does, with the same bits.
#[test]
fn side_by_side_holds_at_any_scale() {
    let (mut lanes, b) = three_chains(5);
    for p in 0..lanes.slots() {
        let k = lanes.block(p);
        lanes.set(p, &(k * 1e13));
    }
    let mut scalar = lanes.clone().without_lanes();
    let (mut x, mut y) = (b.clone(), b.clone());
    assert!(scalar.factor_and_solve(&mut y));
    assert!(
        lanes.factor_and_solve(&mut x),
        "the padding lane failed its pivot test"
    );
    assert!(x
        .iter()
        .zip(y.iter())
        .all(|(p, q)| p.to_bits() == q.to_bits()));
}

/// A singular pivot in one chain fails the factor side by side too.
#[test]
fn a_singular_chain_fails_side_by_side() {
    let (mut chol, b) = three_chains(4);
    let idx = chol.k_index(4, 4).unwrap();
    chol.set(idx, &Matrix3::zeros());
    assert!(chol.has_lanes());
    let mut scalar = chol.clone().without_lanes();
    assert!(!chol.factor_and_solve(&mut b.clone()));
    assert!(!scalar.factor_and_solve(&mut b.clone()));
}

/// Chains of different patterns stay on the scalar factor.
#[test]
fn unlike_chains_are_not_put_side_by_side() {
    let chol = BlockLdl::new(5, &[(1, 0), (2, 1), (4, 3)]);
    assert!(!chol.has_lanes());
    let twins = BlockLdl::new(6, &[(2, 0), (4, 2), (3, 1), (5, 3)]);
    assert!(twins.has_lanes());
}
