//! mvgrasp-render
