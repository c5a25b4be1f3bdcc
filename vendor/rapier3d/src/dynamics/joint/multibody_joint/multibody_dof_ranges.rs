//! The tree sparsity of a multibody: per link, the generalized coordinates its body Jacobian
//! can be non-zero in.
//!
//! A link's body Jacobian (6 x ndofs) has non-zero columns only at its own degrees of freedom
//! and those of its ancestors: a leg link of a floating quadruped touches 6 + 3 of 18 columns.
//! Products over the other columns add exact zeros, so `Multibody` runs its Jacobian, mass-matrix
//! and Coriolis products over these ranges only. The dofs' parents give the tree that the mass
//! matrix is factorized along (`MultibodyMassFactor`).

use super::multibody_link::MultibodyLinkVec;
use super::multibody_mass_factor::NO_PARENT;
use crate::alloc_prelude::*;

/// Per link, its own and its ancestors' degrees of freedom as sorted, merged ranges
/// `(first, len)` of generalized coordinates.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug, Default)]
pub(crate) struct LinkDofRanges {
    /// `(parent, assembly_id, ndofs)` per link, as the ranges were last built for.
    topology: Vec<(usize, usize, usize)>,
    /// Every link's ranges, one after the other.
    ranges: Vec<(usize, usize)>,
    /// Link `i`'s ranges are `ranges[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    /// Per dof, its parent in the dof tree: the previous dof of its joint, else the last dof
    /// of its nearest ancestor link with any (`NO_PARENT` for the first dof of the tree).
    dof_parents: Vec<usize>,
    /// Bumped each time the ranges change: buffers that rely on being zero outside them
    /// record the version they were cleared for.
    version: u64,
}

impl LinkDofRanges {
    /// Rebuilds the ranges if the links' tree or degrees of freedom changed since the last call.
    /// Allocates nothing when they did not.
    pub fn update(&mut self, links: &MultibodyLinkVec) {
        let unchanged = self.topology.len() == links.len()
            && links
                .iter()
                .zip(&self.topology)
                .enumerate()
                .all(|(i, (link, seen))| {
                    *seen
                        == (
                            Self::parent_of(i, link.parent_internal_id),
                            link.assembly_id,
                            link.joint.ndofs(),
                        )
                });
        if unchanged && self.version != 0 {
            return;
        }

        self.topology.clear();
        self.ranges.clear();
        self.offsets.clear();
        self.offsets.push(0);
        self.dof_parents.clear();
        for (i, link) in links.iter().enumerate() {
            let parent = Self::parent_of(i, link.parent_internal_id);
            self.topology
                .push((parent, link.assembly_id, link.joint.ndofs()));
            if parent != usize::MAX {
                for k in self.offsets[parent]..self.offsets[parent + 1] {
                    let range = self.ranges[k];
                    self.ranges.push(range);
                }
            }
            let own = (link.assembly_id, link.joint.ndofs());
            let parent_dof = match self.ranges[self.offsets[i]..].last() {
                Some(last) => last.0 + last.1 - 1,
                None => NO_PARENT,
            };
            for k in 0..own.1 {
                self.dof_parents
                    .push(if k == 0 { parent_dof } else { own.0 + k - 1 });
            }
            if own.1 > 0 {
                let has_ranges = self.ranges.len() > self.offsets[i];
                match self.ranges.last_mut() {
                    Some(last) if has_ranges && last.0 + last.1 == own.0 => last.1 += own.1,
                    _ => self.ranges.push(own),
                }
            }
            self.offsets.push(self.ranges.len());
        }
        self.version += 1;
    }

    fn parent_of(link: usize, parent_internal_id: usize) -> usize {
        if link == 0 {
            usize::MAX
        } else {
            parent_internal_id
        }
    }

    /// The ranges `(first, len)` of link `link`'s own and ancestors' degrees of freedom.
    pub fn of(&self, link: usize) -> &[(usize, usize)] {
        &self.ranges[self.offsets[link]..self.offsets[link + 1]]
    }

    /// Per dof, its parent dof in the tree (`NO_PARENT` for the first).
    pub fn dof_parents(&self) -> &[usize] {
        &self.dof_parents
    }

    /// Changes whenever the ranges do (never 0 once built).
    pub fn version(&self) -> u64 {
        self.version
    }
}
