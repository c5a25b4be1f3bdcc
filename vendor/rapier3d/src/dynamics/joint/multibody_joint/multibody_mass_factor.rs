//! The factorization of a multibody's mass matrix that every contact, limit and motor row
//! is solved against.
//!
//! A multibody's mass matrix `M` (ndofs x ndofs, symmetric positive definite) has a non-zero
//! entry `(i, j)` only where dof `i` is an ancestor of dof `j` in the kinematic tree, or the
//! reverse. Eliminating from the leaves to the root then creates no fill-in:
//! `M = Lᵀ·D·L` with `L` unit lower triangular and non-zero only at ancestor entries, as in
//! MuJoCo's `mj_factorM` / `mj_solveM`. A factorization costs the sum over dofs of
//! (ancestors x depth) instead of n³/3, and each solve the sum of the ancestor counts instead
//! of n². Where the tree form does not apply (a kinematic dof reorders the matrix, or a pivot
//! is not positive), the dense LU with partial pivoting is used instead.

use crate::alloc_prelude::*;
use crate::math::Real;
use na::constraint::{SameNumberOfRows, ShapeConstraint};
use na::{DMatrixView, Dim, Dyn, LU, Matrix, StorageMut};

/// No parent dof: a root of the dof tree.
pub(crate) const NO_PARENT: usize = usize::MAX;

/// `M = Lᵀ·D·L` over the dof tree, or a dense LU.
///
/// `L` is stored by rows, each row holding only the dof's ancestors (parent first), the
/// layout MuJoCo uses: row `k`'s entries are `l[offsets[k]..offsets[k + 1]]`, at the dofs
/// `ancestors[offsets[k]..offsets[k + 1]]`.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug, Default)]
pub struct MultibodyMassFactor {
    /// Per dof, where its row starts in `ancestors` and `l` (n + 1 entries).
    offsets: Vec<usize>,
    /// Each dof's ancestors, nearest first.
    ancestors: Vec<usize>,
    /// `L` at those entries.
    l: Vec<Real>,
    /// `1 / D` per dof.
    inv_d: Vec<Real>,
    /// The dense fallback.
    dense: Option<LU<Real, Dyn, Dyn>>,
}

impl MultibodyMassFactor {
    /// Factorizes `m` over the dof tree given by `parent` (each dof's parent has a smaller
    /// index). Only the lower triangle of `m` at ancestor entries is read. Falls back to the
    /// dense LU of `m` if a pivot is not positive and finite.
    pub(crate) fn factor_tree(&mut self, m: DMatrixView<Real>, parent: &[usize]) {
        let n = m.nrows();
        debug_assert_eq!(parent.len(), n);
        self.dense = None;
        self.offsets.clear();
        self.ancestors.clear();
        self.l.clear();
        self.inv_d.clear();

        // Copy the diagonal into inv_d (inverted below) and the ancestor entries of the lower
        // triangle into the rows: (k, i) with i an ancestor of k.
        for k in 0..n {
            self.offsets.push(self.ancestors.len());
            self.inv_d.push(m[(k, k)]);
            let mut i = parent[k];
            while i != NO_PARENT {
                self.ancestors.push(i);
                self.l.push(m[(k, i)]);
                i = parent[i];
            }
        }
        self.offsets.push(self.ancestors.len());

        // Leaves to root: eliminate row k from its ancestors. Row k's entries after position
        // p are exactly the ancestors of its p-th ancestor, so no fill-in and no search.
        for k in (0..n).rev() {
            let d = self.inv_d[k];
            if !(d > 0.0 && d.is_finite()) {
                self.factor_dense(m);
                return;
            }
            let (row_k, len_k) = (self.offsets[k], self.offsets[k + 1] - self.offsets[k]);
            for p in 0..len_k {
                let i = self.ancestors[row_k + p];
                let l_ki = self.l[row_k + p] / d;
                self.inv_d[i] -= l_ki * self.l[row_k + p];
                let row_i = self.offsets[i];
                for q in p + 1..len_k {
                    self.l[row_i + q - p - 1] -= l_ki * self.l[row_k + q];
                }
                self.l[row_k + p] = l_ki;
            }
            self.inv_d[k] = 1.0 / d;
        }
    }

    /// Factorizes `m` with the dense LU (partial pivoting).
    pub(crate) fn factor_dense(&mut self, m: DMatrixView<Real>) {
        self.dense = Some(LU::new(m.into_owned()));
    }

    /// Solves `M·x = b` in place, column by column. Returns `false` if `M` is singular (dense
    /// fallback only; the tree form has positive pivots by construction).
    pub fn solve_mut<R2: Dim, C2: Dim, S2>(&self, b: &mut Matrix<Real, R2, C2, S2>) -> bool
    where
        S2: StorageMut<Real, R2, C2>,
        ShapeConstraint: SameNumberOfRows<R2, Dyn>,
    {
        if let Some(lu) = &self.dense {
            return lu.solve_mut(b);
        }
        let n = self.inv_d.len();
        assert_eq!(b.nrows(), n, "mass matrix solve: dimension mismatch.");
        // A contiguous copy of each column (on the stack for up to 64 dofs).
        let mut stack = [0.0 as Real; 64];
        let mut heap = Vec::new();
        let x: &mut [Real] = if n <= stack.len() {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap
        };
        for c in 0..b.ncols() {
            for (k, x_k) in x.iter_mut().enumerate() {
                *x_k = b[(k, c)];
            }
            // x = L⁻ᵀ·b: leaves to root.
            for k in (0..n).rev() {
                let x_k = x[k];
                let row = self.offsets[k]..self.offsets[k + 1];
                for (&i, &l_ki) in self.ancestors[row.clone()].iter().zip(&self.l[row]) {
                    x[i] -= l_ki * x_k;
                }
            }
            // x = D⁻¹·x, then x = L⁻¹·x: root to leaves.
            for k in 0..n {
                let row = self.offsets[k]..self.offsets[k + 1];
                let mut x_k = x[k] * self.inv_d[k];
                for (&i, &l_ki) in self.ancestors[row.clone()].iter().zip(&self.l[row]) {
                    x_k -= l_ki * x[i];
                }
                x[k] = x_k;
            }
            for (k, x_k) in x.iter().enumerate() {
                b[(k, c)] = *x_k;
            }
        }
        true
    }

    /// Whether the tree form is in use (`false`: the dense LU).
    pub fn is_tree_sparse(&self) -> bool {
        self.dense.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use na::DMatrix;

    /// A floating base (6 dofs in a chain) with two 3-dof legs: a tree-patterned SPD matrix.
    fn tree_matrix() -> (DMatrix<Real>, Vec<usize>) {
        let parent: Vec<usize> = vec![NO_PARENT, 0, 1, 2, 3, 4, 5, 6, 7, 5, 9, 10];
        let n = parent.len();
        let ancestor = |a: usize, mut b: usize| {
            while b != NO_PARENT {
                if a == b {
                    return true;
                }
                b = parent[b];
            }
            false
        };
        // M = Σ over a few "links" of Jᵀ·J, each J non-zero at one dof's ancestors only.
        let mut m = DMatrix::zeros(n, n);
        for (seed, leaf) in [(1.0, 8usize), (2.0, 11), (3.0, 6), (4.0, 3)] {
            let j = DMatrix::from_fn(6, n, |r, c| {
                if ancestor(c, leaf) {
                    ((r * 7 + c * 3) as Real * 0.37 + seed).sin()
                } else {
                    0.0
                }
            });
            m += j.transpose() * j;
        }
        for k in 0..n {
            m[(k, k)] += 0.5;
        }
        (m, parent)
    }

    #[test]
    fn tree_factor_solves_like_the_dense_lu() {
        let (m, parent) = tree_matrix();
        let mut tree = MultibodyMassFactor::default();
        tree.factor_tree(m.as_view(), &parent);
        assert!(tree.is_tree_sparse());
        let b = DMatrix::from_fn(m.nrows(), 3, |r, c| (r as Real - c as Real * 2.5).cos());
        let mut x_tree = b.clone();
        assert!(tree.solve_mut(&mut x_tree));
        let mut x_dense = b.clone();
        assert!(LU::new(m.clone()).solve_mut(&mut x_dense));
        assert!((&x_tree - &x_dense).amax() < 1.0e-4 * x_dense.amax().max(1.0));
        assert!((&m * &x_tree - &b).amax() < 1.0e-3);
    }

    #[test]
    fn a_non_positive_pivot_falls_back_to_the_dense_lu() {
        let (mut m, parent) = tree_matrix();
        m[(11, 11)] = -1.0;
        let mut factor = MultibodyMassFactor::default();
        factor.factor_tree(m.as_view(), &parent);
        assert!(!factor.is_tree_sparse());
        let mut x = DMatrix::from_element(m.nrows(), 1, 1.0);
        let solved = factor.solve_mut(&mut x);
        let mut x_dense = DMatrix::from_element(m.nrows(), 1, 1.0);
        assert_eq!(solved, LU::new(m).solve_mut(&mut x_dense));
        assert_eq!(x, x_dense);
    }
}
