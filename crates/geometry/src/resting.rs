//! The one way the project chooses the pose an object rests in on the table: for planning,
//! for the grasp and RGB-D datasets, for `grasps` and for the evaluations.

use std::path::PathBuf;

use crate::error::{GeometryError, Result};
use crate::mesh::TriangleMesh;
use crate::stable_poses::{StablePose, StablePoseParams, stable_poses};

/// The poses an object is offered in, in order: its stable poses that neither roll nor
/// topple, most probable first; when it has none (a ball, a can that only rests on its side),
/// its marginal poses, most probable first, so that every object can be placed. Pose `k` of a
/// command (`plan --stable-pose K`, `grasps --pose K`) is the `k`-th offered pose.
#[derive(Clone, Debug, PartialEq)]
pub struct RestingPoses {
    /// Every stable pose of any probability, most probable first.
    pub all: Vec<StablePose>,
    /// Indices into `all` of the offered poses, in order.
    pub offered: Vec<usize>,
    origin: PathBuf,
}

impl RestingPoses {
    /// The resting poses of `mesh`.
    ///
    /// # Errors
    /// [`GeometryError::Degenerate`] for a flat mesh (it has no stable pose).
    pub fn of(mesh: &TriangleMesh) -> Result<Self> {
        let params = StablePoseParams {
            min_probability: 0.0,
            ..StablePoseParams::default()
        };
        let all = stable_poses(mesh, &params)?;
        let steady: Vec<usize> = (0..all.len()).filter(|&i| !all[i].marginal).collect();
        let offered = if steady.is_empty() {
            (0..all.len()).collect()
        } else {
            steady
        };
        Ok(Self {
            all,
            offered,
            origin: mesh.origin().to_path_buf(),
        })
    }

    /// Whether the offered poses are marginal ones (the object has no steady pose).
    pub fn only_marginal(&self) -> bool {
        self.offered.iter().all(|&i| self.all[i].marginal)
    }

    /// How many poses are offered.
    pub fn len(&self) -> usize {
        self.offered.len()
    }

    /// Whether no pose is offered.
    pub fn is_empty(&self) -> bool {
        self.offered.is_empty()
    }

    /// The offered poses in order, each with its index in [`Self::all`].
    pub fn iter(&self) -> impl Iterator<Item = (usize, &StablePose)> {
        self.offered.iter().map(|&i| (i, &self.all[i]))
    }

    /// The `k`-th offered pose, with its index in [`Self::all`].
    ///
    /// # Errors
    /// [`GeometryError::NoSuchPose`] when fewer than `k + 1` poses are offered.
    pub fn get(&self, k: usize) -> Result<(usize, &StablePose)> {
        self.iter().nth(k).ok_or_else(|| GeometryError::NoSuchPose {
            asked: k,
            offered: self.len(),
            path: self.origin.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::{Category, generate};

    #[test]
    fn steady_poses_come_first_and_a_pose_past_the_list_is_an_error() {
        let mug = generate(Category::Mug, 0, 0).unwrap().mesh;
        let rest = RestingPoses::of(&mug).unwrap();
        assert!(!rest.only_marginal());
        assert!(rest.iter().all(|(_, p)| !p.marginal));
        // Most probable first, and the chosen pose is the first steady one of the full list.
        let (first, _) = rest.get(0).unwrap();
        assert_eq!(Some(first), rest.all.iter().position(|p| !p.marginal));
        let probabilities: Vec<f32> = rest.iter().map(|(_, p)| p.probability).collect();
        assert!(
            probabilities.windows(2).all(|w| w[0] >= w[1]),
            "{probabilities:?}"
        );
        let err = rest.get(rest.len()).unwrap_err().to_string();
        assert!(err.contains(&format!("offers {}", rest.len())), "{err}");
    }

    #[test]
    fn an_object_with_only_marginal_poses_is_still_placed() {
        let (vertices, triangles) = parry3d::shape::Ball::new(0.03).to_trimesh(16, 16);
        let ball = TriangleMesh::new(vertices, triangles).unwrap();
        let rest = RestingPoses::of(&ball).unwrap();
        assert!(!rest.is_empty() && rest.only_marginal());
        assert_eq!(rest.get(0).unwrap().0, 0);
    }
}
