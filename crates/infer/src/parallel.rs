//! How many threads the heavy ops (convolution, linear) may use.

/// How many threads an op may use. Results do not depend on it: on a given machine every value
/// comes out the same to the bit whatever the thread count (the crate's tests check this; faer
/// may pick other SIMD kernels on another CPU, so bits can differ between machines).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// The calling thread only: the right choice when the caller already runs models or
    /// images in parallel.
    #[default]
    Sequential,
    /// Up to `threads` tasks on the current rayon thread pool; `0` means as many as the pool
    /// has threads.
    Rayon {
        /// The most tasks an op splits into; `0` for the pool's thread count.
        threads: usize,
    },
}

impl Parallelism {
    /// The whole current rayon pool.
    pub fn all_threads() -> Self {
        Self::Rayon { threads: 0 }
    }

    /// The number of tasks this allows, at least 1.
    pub fn threads(self) -> usize {
        match self {
            Self::Sequential => 1,
            Self::Rayon { threads: 0 } => rayon::current_num_threads().max(1),
            Self::Rayon { threads } => threads,
        }
    }

    /// The same parallelism in faer's terms.
    pub(crate) fn faer(self) -> faer::Par {
        match self.threads() {
            1 => faer::Par::Seq,
            n => faer::Par::rayon(n),
        }
    }
}
