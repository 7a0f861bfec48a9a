//! One thread of the process at a time creates or destroys wgpu instances and devices:
//! drivers and the Vulkan loader race otherwise.

use std::sync::{Condvar, Mutex};

/// Vulkan instances and devices created or destroyed on several threads at once race in
/// drivers and the loader (NVIDIA's among them): this process does one at a time.
static SECTION_BUSY: Mutex<bool> = Mutex::new(false);
static SECTION_FREE: Condvar = Condvar::new();

thread_local! {
    /// Whether this thread is in a section (one inside another would wait forever).
    static IN_SECTION: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// A section in which this thread alone creates or destroys instances and devices.
pub(crate) struct Section;

impl Section {
    pub(crate) fn begin() -> Self {
        assert!(
            !IN_SECTION.get(),
            "a GPU context opened or dropped inside another's opening or drop"
        );
        let mut busy = SECTION_BUSY.lock().unwrap_or_else(|e| e.into_inner());
        while *busy {
            busy = SECTION_FREE.wait(busy).unwrap_or_else(|e| e.into_inner());
        }
        *busy = true;
        IN_SECTION.set(true);
        Self
    }
}

impl Drop for Section {
    fn drop(&mut self) {
        IN_SECTION.set(false);
        *SECTION_BUSY.lock().unwrap_or_else(|e| e.into_inner()) = false;
        SECTION_FREE.notify_one();
    }
}

/// Ends the section a context's drop began, once the fields before it have dropped.
#[derive(Default)]
pub(crate) struct SectionEnd(pub(crate) Option<Section>);

impl Clone for SectionEnd {
    fn clone(&self) -> Self {
        Self(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One thread at a time in a section: a second waits until the first ends it.
    #[test]
    fn sections_exclude_each_other() {
        use std::sync::atomic::{AtomicU32, Ordering};
        use std::sync::Arc;
        let inside = Arc::new(AtomicU32::new(0));
        let most = Arc::new(AtomicU32::new(0));
        let threads: Vec<_> = (0..4)
            .map(|_| {
                let (inside, most) = (inside.clone(), most.clone());
                std::thread::spawn(move || {
                    for _ in 0..50 {
                        let _section = Section::begin();
                        let now = inside.fetch_add(1, Ordering::SeqCst) + 1;
                        most.fetch_max(now, Ordering::SeqCst);
                        std::thread::yield_now();
                        inside.fetch_sub(1, Ordering::SeqCst);
                    }
                })
            })
            .collect();
        for t in threads {
            t.join().unwrap();
        }
        assert_eq!(most.load(Ordering::SeqCst), 1);
    }
}
