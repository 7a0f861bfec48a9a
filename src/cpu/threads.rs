//! The CPU engine's work split over cores: particles in fixed chunks of [`CHUNK`], each
//! chunk's work done whole by one thread, and per-chunk results combined in chunk order.
//! The chunks, not the threads, fix every summation order, so a run gives the same bits
//! on any number of threads.

use crate::error::PowderError;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// Particles per chunk. Fixed (never derived from the thread count): it decides the order
/// of the reductions, hence the bits of the results.
pub const CHUNK: usize = 512;

/// The particle ranges of chunks of `chunk` over `n` particles.
pub fn chunks(n: usize, chunk: usize) -> impl ExactSizeIterator<Item = Range<usize>> + Clone {
    // (a chunk of 0 is taken as 1)
    let chunk = chunk.max(1);
    (0..n.div_ceil(chunk)).map(move |c| c * chunk..((c + 1) * chunk).min(n))
}

/// The most threads a CPU engine may be given.
pub const MAX_THREADS: usize = 1024;

/// How many threads a CPU engine uses, and the pool they come from.
#[derive(Clone, Debug)]
pub struct Threads {
    /// `None`: the current rayon pool (rayon's global pool: all cores unless configured).
    pool: Option<Arc<rayon::ThreadPool>>,
    count: usize,
    /// Particles per chunk ([`CHUNK`]).
    chunk: usize,
}

impl Default for Threads {
    /// Every core, through rayon's global pool.
    fn default() -> Self {
        Self {
            pool: None,
            count: rayon::current_num_threads(),
            chunk: CHUNK,
        }
    }
}

impl Threads {
    /// `count` threads of a pool of their own; 0 means every core ([`Threads::default`]),
    /// 1 runs on the calling thread without a pool.
    pub fn new(count: usize) -> Result<Self, PowderError> {
        if count > MAX_THREADS {
            return Err(crate::ParamError::new(
                "threads",
                format!(
                    "{count} threads is more than the {MAX_THREADS} allowed (0 means every core)"
                ),
            )
            .into());
        }
        match count {
            0 => Ok(Self::default()),
            1 => Ok(Self {
                pool: None,
                count: 1,
                chunk: CHUNK,
            }),
            _ => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(count)
                    .thread_name(|i| format!("powder-cpu-{i}"))
                    .build()
                    .map_err(|e| {
                        PowderError::Run(format!("cannot start {count} CPU threads: {e}"))
                    })?;
                Ok(Self {
                    pool: Some(Arc::new(pool)),
                    count,
                    chunk: CHUNK,
                })
            }
        }
    }

    /// The number of threads.
    pub fn count(&self) -> usize {
        self.count
    }

    /// With chunks of `chunk` particles (at least 1) instead of [`CHUNK`]. The trajectory
    /// does not depend on it, only the last bits of the energy ledger's sums; small chunks
    /// put chunk and wall-piece boundaries everywhere (tests).
    pub fn with_chunk(mut self, chunk: usize) -> Self {
        self.chunk = chunk.max(1);
        self
    }

    /// Particles per chunk.
    pub fn chunk(&self) -> usize {
        self.chunk
    }

    /// `f` run on one of the pool's threads (rayon's global pool for every core), so the
    /// parallel sections it opens need no hand-over from an outside thread; on the calling
    /// thread with one thread. Where engines share a pool and run from several threads at
    /// once, a waiting thread may run another's whole `f` (results unchanged).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(pool) => pool.install(f),
            None if self.count > 1 => rayon::scope(|_| f()),
            None => f(),
        }
    }

    /// `f` with the parallel sections it opens (rayon's, as in set-up checks outside the
    /// step) on these threads only: with one thread, a pool of one.
    pub fn install_all<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        if self.count == 1 {
            if let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                return pool.install(f);
            }
        }
        self.install(f)
    }

    /// `f` applied to every item, results in item order: on the calling thread with one
    /// thread or one item, otherwise spread over the threads (each item whole on one).
    pub fn map<T: Send, R: Send>(&self, items: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
        if self.count <= 1 || items.len() <= 1 {
            return items.into_iter().map(f).collect();
        }
        let work = || items.into_par_iter().with_max_len(1).map(&f).collect();
        match &self.pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }
}

impl Threads {
    /// [`Self::map`], but on the calling thread when the items hold no more than a chunk
    /// of `work` (particles, contacts) in all: handing tiny items to the pool costs more
    /// than they do (the wall pieces of a small scene).
    pub fn map_work<T: Send, R: Send>(
        &self,
        work: usize,
        items: Vec<T>,
        f: impl Fn(T) -> R + Sync,
    ) -> Vec<R> {
        if work <= self.chunk {
            return items.into_iter().map(f).collect();
        }
        self.map(items, f)
    }

    /// `f` applied to every element of `items`, results in element order, written in
    /// place by the threads in runs of at least a chunk (on the calling thread with one
    /// thread or no more than a chunk of elements). Elementwise: no order to keep.
    pub fn map_slice<T: Sync, R: Send>(
        &self,
        items: &[T],
        f: impl Fn(&T) -> R + Sync + Send,
    ) -> Vec<R> {
        if self.count <= 1 || items.len() <= self.chunk {
            return items.iter().map(f).collect();
        }
        let work = || items.par_iter().with_min_len(self.chunk).map(&f).collect();
        match &self.pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn install_all_keeps_rayon_to_the_threads_asked_for() {
        for n in [1, 2, 3] {
            let t = Threads::new(n).unwrap();
            assert_eq!(t.install_all(rayon::current_num_threads), n);
        }
    }

    #[test]
    fn chunks_cover_every_particle_once_in_order() {
        for n in [0, 1, CHUNK - 1, CHUNK, CHUNK + 1, 5 * CHUNK + 3] {
            let all: Vec<usize> = chunks(n, CHUNK).flatten().collect();
            assert_eq!(all, (0..n).collect::<Vec<_>>());
            assert!(chunks(n, CHUNK).all(|r| !r.is_empty() && r.len() <= CHUNK));
        }
    }

    #[test]
    fn map_keeps_item_order_on_any_thread_count() {
        let items: Vec<usize> = (0..1000).collect();
        let want: Vec<usize> = items.iter().map(|x| x * x).collect();
        for t in [1, 2, 3] {
            let threads = Threads::new(t).unwrap();
            assert_eq!(threads.count(), t);
            assert_eq!(threads.map(items.clone(), |x| x * x), want);
        }
        let big: Vec<usize> = (0..3 * CHUNK + 5).collect();
        let squares: Vec<usize> = big.iter().map(|x| x * x).collect();
        for t in [1, 2, 3] {
            let threads = Threads::new(t).unwrap();
            assert_eq!(threads.map_slice(&big, |x| x * x), squares);
            assert_eq!(threads.map_slice(&items, |x| x * x), want);
        }
        let err = Threads::new(MAX_THREADS + 1).unwrap_err().to_string();
        assert!(err.contains("threads") && err.contains("1025"), "{err}");
    }
}
