//! mvgrasp-infer
