//! Which image is on disk (and on the page): the rule that a render never replaces a more
//! converged image of the same scene.
//!
//! A render of another scene always replaces the image (it shows the latest save). A render of
//! the same scene (restarted after a save was cancelled by a broken one, say) writes only once
//! it has caught up: a full-size image beats a preview, then more iterations beat fewer.

use std::sync::{Arc, Mutex};

use crate::cli::identity::SceneId;

/// How converged an image is and of which scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Written {
    pub scene: SceneId,
    /// A full-size render (not a preview).
    pub full: bool,
    pub iterations: u32,
}

impl Written {
    /// Whether this image may replace `old` (the one written last, if any).
    pub fn replaces(&self, old: Option<&Written>) -> bool {
        match old {
            Some(old) if old.scene == self.scene => {
                (self.full, self.iterations) >= (old.full, old.iterations)
            }
            _ => true,
        }
    }
}

/// The last image written, shared by the rounds (one at a time writes).
#[derive(Debug, Clone, Default)]
pub struct OnDisk(Arc<Mutex<Option<Written>>>);

impl OnDisk {
    /// Writes with `write` when `image` may replace what is on disk, and records it when that
    /// succeeds; `Ok(false)` when the image on disk is kept. When the file is gone
    /// (`!present`: deleted by hand), any image is better than none.
    pub fn write_if_better<E>(
        &self,
        image: Written,
        present: bool,
        write: impl FnOnce() -> Result<(), E>,
    ) -> Result<bool, E> {
        // A panic elsewhere while holding the lock leaves plain data.
        let mut last = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if present && !image.replaces(last.as_ref()) {
            return Ok(false);
        }
        write()?;
        *last = Some(image);
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sppm_lang::EvalOptions;

    fn ids() -> (SceneId, SceneId) {
        let id = |bg: &str| {
            let text = format!("background rgb <{bg}, 0, 0>\n");
            let loaded =
                sppm_lang::internals::eval::load_source("k.scn", &text, &EvalOptions::default());
            SceneId::of(loaded.scene.as_ref().expect("a scene"))
        };
        (id("1"), id("0.5"))
    }

    #[test]
    fn only_a_more_converged_image_of_the_same_scene_replaces_it() {
        let (a, b) = ids();
        let w = |scene, full, iterations| Written {
            scene,
            full,
            iterations,
        };
        let done = w(a, true, 64);
        assert!(done.replaces(None), "nothing on disk yet");
        assert!(!w(a, false, 4).replaces(Some(&done)), "a preview");
        assert!(!w(a, true, 1).replaces(Some(&done)), "fewer iterations");
        assert!(w(a, true, 64).replaces(Some(&done)), "as many");
        assert!(w(a, true, 65).replaces(Some(&done)), "more");
        assert!(
            w(a, true, 1).replaces(Some(&w(a, false, 4))),
            "full over preview"
        );
        assert!(w(b, false, 1).replaces(Some(&done)), "another scene");
    }

    #[test]
    fn on_disk_writes_only_what_replaces_and_records_only_what_was_written() {
        let (a, _) = ids();
        let disk = OnDisk::default();
        let mut writes = 0;
        let full = |iterations| Written {
            scene: a,
            full: true,
            iterations,
        };
        let ok = |n: &mut i32| {
            *n += 1;
            Ok::<(), ()>(())
        };
        assert_eq!(
            disk.write_if_better(full(10), true, || ok(&mut writes)),
            Ok(true)
        );
        assert_eq!(
            disk.write_if_better(full(3), true, || ok(&mut writes)),
            Ok(false)
        );
        assert_eq!(writes, 1, "the image of 3 iterations was not written");
        // A failed write is not recorded: the next image of fewer iterations than it still
        // compares with the 10 on disk.
        assert_eq!(disk.write_if_better(full(20), true, || Err(())), Err(()));
        assert_eq!(
            disk.write_if_better(full(12), true, || ok(&mut writes)),
            Ok(true)
        );
        assert_eq!(writes, 2);
        // The file deleted: the image of fewer iterations is written after all.
        assert_eq!(
            disk.write_if_better(full(1), false, || ok(&mut writes)),
            Ok(true)
        );
        assert_eq!(writes, 3);
    }
}
