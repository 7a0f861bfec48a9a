//! Pages: the lists' entries, and the particle state's two buffers, in several buffers of
//! whole windows where one buffer would exceed the adapter's largest. A window's
//! dispatches bind its page whole, and the next or previous page (read only) where its
//! neighbours' data lie there; the pages' bytes one after the other are the one buffer's
//! (checkpoints do not change). See `docs/gpu_rebuild.md`, *Pages*.

use crate::gpu::window::Windows;

/// How a buffer blocked by window is cut into pages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pages {
    /// Windows a page holds (all of them with one page).
    pub windows: u64,
    /// Pages.
    pub count: u64,
}

/// The fewest windows a page holds: a window's neighbours then lie in its own page and
/// at most one other.
pub const MIN_PAGE_WINDOWS: u64 = 3;

impl Pages {
    /// One page: the one buffer, bound whole or a window and its neighbours at a time.
    pub fn one(windows: &Windows) -> Self {
        Self {
            windows: windows.count,
            count: 1,
        }
    }

    /// The pages of a buffer of `block` bytes a window: one where all windows fit `most`
    /// bytes (the largest buffer), else pages of as many windows as `page` bytes hold (at
    /// most a binding: a page is bound whole). `None` where a page would hold fewer than
    /// [`MIN_PAGE_WINDOWS`].
    pub fn of(windows: &Windows, block: u64, (most, page): (u64, u64)) -> Option<Self> {
        if windows.count * block <= most {
            return Some(Self::one(windows));
        }
        let per = page / block.max(1);
        (per >= MIN_PAGE_WINDOWS).then(|| Self {
            windows: per,
            count: windows.count.div_ceil(per),
        })
    }

    /// Whether there are several.
    pub fn paged(&self) -> bool {
        self.count > 1
    }

    /// The page holding window w.
    pub fn page_of(&self, w: u64) -> u64 {
        w / self.windows
    }

    /// Page p's first window and its windows, of `total`.
    pub fn range(&self, p: u64, total: u64) -> (u64, u64) {
        let first = p * self.windows;
        (first, self.windows.min(total - first))
    }

    /// The other page window w's dispatches bind (read only): the previous where w opens
    /// its page or lies in the last, else the next (never read where w's neighbours are all
    /// in its page).
    pub fn other(&self, w: u64) -> u64 {
        let p = self.page_of(w);
        if p > 0 && (w.is_multiple_of(self.windows) || p + 1 == self.count) {
            p - 1
        } else {
            p + 1
        }
    }

    /// (page, byte within it) of byte `at` of the buffer the pages stand for, `block`
    /// bytes a window.
    pub fn locate(&self, at: u64, block: u64) -> (u64, u64) {
        let page = self.windows * block;
        (at / page, at % page)
    }

    /// The `win` uniform's fields of a paged buffer (the entries' `rec_*`, the state's
    /// `st_*`) for window w whose binding of a one-page buffer starts at window `bound`: the
    /// first window of the buffer's binding, the end of the windows it holds, the first
    /// window of the other page's binding.
    pub fn params(&self, w: u64, bound: u64, total: u64) -> [u32; 3] {
        if !self.paged() {
            return [bound as u32, (bound + 3).min(total) as u32, 0];
        }
        let (first, len) = self.range(self.page_of(w), total);
        let (other, _) = self.range(self.other(w), total);
        [first as u32, (first + len) as u32, other as u32]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_hold_whole_windows_and_pair_each_window_with_its_neighbours() {
        let windows = Windows::of(1000, 64).unwrap();
        assert_eq!(windows.count, 16);
        // fits the largest buffer: one page
        let one = Pages::of(&windows, 256, (16 * 256, 1024)).unwrap();
        assert_eq!(one, Pages::one(&windows));
        assert_eq!(one.params(5, 4, 16), [4, 7, 0]);
        // pages of 3 windows: 6 pages, the last of one window
        let p = Pages::of(&windows, 256, (16 * 256 - 1, 3 * 256 + 255)).unwrap();
        assert_eq!((p.windows, p.count), (3, 6));
        assert_eq!(p.range(5, 16), (15, 1));
        for w in 0..16u64 {
            let bound = windows.bound(w);
            let [first, end, other] = p.params(w, bound, 16).map(u64::from);
            assert!(first <= w && w < end && end - first <= 3);
            // every window the bindings of w's dispatches cover (its neighbours, and what
            // the search accepts) is in the page or the other one
            let (o_first, o_len) = p.range(p.other(w), 16);
            assert_eq!(other, o_first);
            assert_ne!(p.other(w), p.page_of(w));
            for v in bound..bound + windows.covered() {
                assert!(
                    (first..end).contains(&v) || (o_first..o_first + o_len).contains(&v),
                    "window {w}: neighbour {v}"
                );
            }
        }
        assert_eq!(p.locate(3 * 256 + 10, 256), (1, 10));
        // a page of fewer than three windows is refused
        assert_eq!(Pages::of(&windows, 256, (1024, 2 * 256 + 255)), None);
    }
}
