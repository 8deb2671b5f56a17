//! mvgrasp-grasp
