//! mvgrasp: the pipeline.
