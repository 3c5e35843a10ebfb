//! Watching the files a scene depends on, for `sppm-lang watch`.
//!
//! The watcher is told the exact set of files the last evaluation read (the scene, its includes,
//! images, meshes). It watches each file's *parent directory*, not the file: editors that save by
//! writing a temporary file and renaming it over the original (vim, many IDEs), or by deleting
//! and recreating it, replace the inode a file watch would be attached to, while the directory
//! watch sees the new file under the same name. Events for other names in those directories
//! (backup files `file~`, `.#file`, swap files, our own output images) are ignored. A dependency
//! whose directory does not exist yet is polled, so creating it triggers a change.
//!
//! No save is lost while an evaluation runs: the caller keeps the previous set watched during
//! it, and replacing the set keeps the events that arrived meanwhile (for the old set or the
//! new one) for the next wait. A file in a folder the old set did not cover is reported when
//! it was modified after the evaluation began ([`DependencyWatcher::set_dependencies_after`]).
//!
//! Events are batched: after the first relevant event the watcher waits until the files have been
//! quiet for [`QUIET`] or [`MAX_BATCH`] has passed since the first event, so one save (which
//! editors often turn into several events) is one change.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use notify::{EventKind, RecommendedWatcher, RecursiveMode, Watcher};

/// How long the files must be quiet before a batch of events is reported.
pub const QUIET: Duration = Duration::from_millis(100);
/// The longest a batch waits for quiet after its first event.
pub const MAX_BATCH: Duration = Duration::from_millis(500);
/// How often dependencies in directories that do not exist yet are looked for.
pub const POLL: Duration = Duration::from_millis(250);
/// How far a file's modification time may lag the clock (file systems stamp times with a
/// coarse clock, some to 2 s): see [`DependencyWatcher::set_dependencies_after`].
pub const CLOCK_MARGIN: Duration = Duration::from_secs(2);

/// One batch of changes.
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    /// The changed dependencies, sorted.
    pub files: Vec<PathBuf>,
    /// When the first event of the batch arrived.
    pub first_event: Instant,
}

impl Batch {
    fn new(files: BTreeSet<PathBuf>, first_event: Instant) -> Self {
        Self {
            files: files.into_iter().collect(),
            first_event,
        }
    }
}

/// Watches a set of files through their parent directories.
pub struct DependencyWatcher {
    watcher: RecommendedWatcher,
    events: Receiver<notify::Result<notify::Event>>,
    /// Normalised paths of the files we report changes for.
    files: HashSet<PathBuf>,
    /// Directories currently watched.
    dirs: HashSet<PathBuf>,
    /// Dependencies whose directory is missing: polled.
    missing: BTreeSet<PathBuf>,
    /// Changes seen outside a wait (see `set_dependencies`), and when the first was seen.
    pending: BTreeSet<PathBuf>,
    pending_since: Option<Instant>,
}

impl DependencyWatcher {
    pub fn new() -> Result<Self, String> {
        let (tx, events) = channel();
        let watcher = notify::recommended_watcher(move |e| {
            let _ = tx.send(e);
        })
        .map_err(|e| format!("cannot start the file watcher: {e}"))?;
        Ok(Self {
            watcher,
            events,
            files: HashSet::new(),
            dirs: HashSet::new(),
            missing: BTreeSet::new(),
            pending: BTreeSet::new(),
            pending_since: None,
        })
    }

    /// Replaces the watched set by `files`: new directories are watched, directories no
    /// dependency lives in any more are dropped. Events that arrived since the last wait, for a
    /// file of the old set or of the new one, are kept: the next wait reports them.
    pub fn set_dependencies<I, P>(&mut self, files: I) -> Result<(), String>
    where
        I: IntoIterator<Item = P>,
        P: AsRef<Path>,
    {
        self.replace(files, None)
    }

    /// Like [`set_dependencies`](Self::set_dependencies), for the files an evaluation that
    /// started at `read_from` read. Until now a folder not watched before was not watched: a
    /// file in it modified since `read_from` (less [`CLOCK_MARGIN`]) may have changed after the
    /// evaluation read it, so it is reported as changed by the next wait.
    pub fn set_dependencies_after<I, P>(
        &mut self,
        files: I,
        read_from: SystemTime,
    ) -> Result<(), String>
    where
        I: IntoIterator<Item = P>,
        P: AsRef<Path>,
    {
        self.replace(files, Some(read_from))
    }

    fn replace<I, P>(&mut self, files: I, read_from: Option<SystemTime>) -> Result<(), String>
    where
        I: IntoIterator<Item = P>,
        P: AsRef<Path>,
    {
        let mut new_files = HashSet::new();
        let mut missing = BTreeSet::new();
        let mut wanted = HashSet::new();
        for file in files {
            let path = normalize(file.as_ref());
            // A symbolic link's file is edited where the link points (its own folder sees no
            // change): the target is watched too.
            let target = std::fs::symlink_metadata(&path)
                .ok()
                .filter(|m| m.file_type().is_symlink())
                .and_then(|_| path.canonicalize().ok());
            for path in std::iter::once(path).chain(target) {
                match path.parent().filter(|d| d.is_dir()) {
                    Some(dir) => {
                        wanted.insert(dir.to_path_buf());
                    }
                    None => {
                        missing.insert(path.clone());
                    }
                }
                new_files.insert(path);
            }
        }
        // Events queued while the files were being read belong to the next batch.
        self.files.extend(new_files.iter().cloned());
        self.collect_pending();
        self.files = new_files;
        self.missing = missing;
        for dir in self.dirs.difference(&wanted).cloned().collect::<Vec<_>>() {
            let _ = self.watcher.unwatch(&dir);
            self.dirs.remove(&dir);
        }
        let mut newly = HashSet::new();
        for dir in wanted {
            if !self.dirs.contains(&dir) {
                self.watcher
                    .watch(&dir, RecursiveMode::NonRecursive)
                    .map_err(|e| format!("cannot watch `{}`: {e}", dir.display()))?;
                self.dirs.insert(dir.clone());
                newly.insert(dir);
            }
        }
        if let Some(read_from) = read_from {
            let since = read_from.checked_sub(CLOCK_MARGIN).unwrap_or(UNIX_EPOCH);
            let late = self.files.iter().filter(|f| {
                f.parent().is_some_and(|d| newly.contains(d))
                    && std::fs::metadata(f)
                        .and_then(|m| m.modified())
                        .is_ok_and(|t| t >= since)
            });
            let late: Vec<PathBuf> = late.cloned().collect();
            if !late.is_empty() {
                self.pending.extend(late);
                self.pending_since.get_or_insert_with(Instant::now);
            }
        }
        Ok(())
    }

    /// Moves the events already queued into the pending batch (without waiting).
    fn collect_pending(&mut self) {
        while let Ok(event) = self.events.try_recv() {
            // As in `wait_batch`: an error is a change.
            if let Ok(event) = event {
                if !self.is_relevant(&event) {
                    continue;
                }
                for p in event.paths {
                    if self.files.contains(&p) {
                        self.pending.insert(p);
                    }
                }
            }
            self.pending_since.get_or_insert_with(Instant::now);
        }
    }

    /// Blocks until a batch of changes to the dependencies arrives and returns the changed
    /// files, or returns `None` when `deadline` passes or `stop()` says so first (checked at
    /// least every [`POLL`]).
    #[cfg(test)]
    pub fn wait(
        &mut self,
        deadline: Option<Instant>,
        stop: &dyn Fn() -> bool,
    ) -> Option<Vec<PathBuf>> {
        self.wait_batch(deadline, stop).map(|b| b.files)
    }

    /// Like `wait` (the tests' form, which returns the files only), also telling when the
    /// first event of the batch arrived (the start of the save-to-picture latency).
    pub fn wait_batch(
        &mut self,
        deadline: Option<Instant>,
        stop: &dyn Fn() -> bool,
    ) -> Option<Batch> {
        // Changes seen while the dependencies were replaced open the batch.
        let mut changed = std::mem::take(&mut self.pending);
        let mut first = self.pending_since.take();
        loop {
            if stop() {
                return None;
            }
            let now = Instant::now();
            if let Some(start) = first {
                if now >= start + MAX_BATCH {
                    return Some(Batch::new(changed, start));
                }
            } else if deadline.is_some_and(|d| now >= d) {
                return None;
            }
            let timeout = match first {
                Some(start) => QUIET.min(start + MAX_BATCH - now),
                None => POLL,
            };
            match self.events.recv_timeout(timeout) {
                Ok(Ok(event)) => {
                    if self.is_relevant(&event) {
                        for p in &event.paths {
                            if self.files.contains(p) {
                                changed.insert(p.clone());
                            }
                        }
                        first.get_or_insert(Instant::now());
                    }
                }
                // The watcher reports an error (e.g. a directory vanished): treat the set as
                // changed so that the caller re-evaluates and re-watches.
                Ok(Err(_)) => {
                    first.get_or_insert(Instant::now());
                }
                Err(RecvTimeoutError::Timeout) => {
                    if let Some(start) = first {
                        // Quiet long enough.
                        return Some(Batch::new(changed, start));
                    }
                    changed.extend(self.poll_missing());
                    if !changed.is_empty() {
                        first = Some(Instant::now());
                    }
                }
                Err(RecvTimeoutError::Disconnected) => return None,
            }
        }
    }

    fn is_relevant(&self, event: &notify::Event) -> bool {
        !matches!(event.kind, EventKind::Access(_))
            && event.paths.iter().any(|p| self.files.contains(p))
    }

    /// Dependencies whose directory has appeared since: watch it, and report the file if it
    /// exists now.
    fn poll_missing(&mut self) -> Vec<PathBuf> {
        let mut appeared = Vec::new();
        for path in self.missing.clone() {
            let Some(dir) = path.parent() else { continue };
            if dir.is_dir() {
                if self.watcher.watch(dir, RecursiveMode::NonRecursive).is_ok() {
                    self.dirs.insert(dir.to_path_buf());
                    self.missing.remove(&path);
                }
                if path.exists() {
                    appeared.push(path);
                }
            }
        }
        appeared
    }
}

/// An absolute path with the directory part resolved through symlinks where it exists, so that
/// it compares equal to the paths the OS reports in events.
pub fn normalize(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => match dir.canonicalize() {
            Ok(dir) => dir.join(name),
            Err(_) => abs.clone(),
        },
        _ => abs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn wait_once(w: &mut DependencyWatcher) -> Option<Vec<PathBuf>> {
        w.wait(Some(Instant::now() + Duration::from_secs(5)), &|| false)
    }

    fn settle(w: &mut DependencyWatcher) {
        // Drain anything left from setting up the files.
        while w
            .wait(Some(Instant::now() + Duration::from_millis(300)), &|| false)
            .is_some()
        {}
    }

    #[test]
    fn reports_in_place_write_and_ignores_other_files() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("a.scn");
        fs::write(&scene, "1").unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&scene]).unwrap();
        settle(&mut w);
        fs::write(dir.path().join("a.scn~"), "backup").unwrap();
        fs::write(dir.path().join("out.png"), "x").unwrap();
        assert_eq!(
            w.wait(Some(Instant::now() + Duration::from_millis(600)), &|| false),
            None,
            "writes to other files in the folder are not changes"
        );
        fs::write(&scene, "2").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&scene)]));
    }

    /// A scene (or include, image, mesh) reached through a symbolic link: an edit of the
    /// file it points to, in another folder, is a change.
    #[cfg(unix)]
    #[test]
    fn edits_through_a_symbolic_link_are_seen() {
        let dir = tempfile::tempdir().unwrap();
        let (real, links) = (dir.path().join("real"), dir.path().join("links"));
        fs::create_dir(&real).unwrap();
        fs::create_dir(&links).unwrap();
        let target = real.join("s.scn");
        fs::write(&target, "1").unwrap();
        let link = links.join("s.scn");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&link]).unwrap();
        settle(&mut w);
        fs::write(&target, "2").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&target)]));
    }

    #[test]
    fn rename_over_and_delete_recreate_are_seen() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("b.scn");
        fs::write(&scene, "1").unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&scene]).unwrap();
        settle(&mut w);
        let tmp = dir.path().join(".b.scn.swp");
        fs::write(&tmp, "2").unwrap();
        fs::rename(&tmp, &scene).unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&scene)]));
        fs::remove_file(&scene).unwrap();
        fs::write(&scene, "3").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&scene)]));
        // And the watch still works after both.
        fs::write(&scene, "4").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&scene)]));
    }

    #[test]
    fn a_burst_of_saves_is_batched() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("c.scn");
        fs::write(&scene, "0").unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&scene]).unwrap();
        settle(&mut w);
        let writer = {
            let scene = scene.clone();
            std::thread::spawn(move || {
                let mut times = Vec::new();
                for i in 0..50 {
                    fs::write(&scene, i.to_string()).unwrap();
                    times.push(Instant::now());
                    std::thread::sleep(Duration::from_millis(20));
                }
                times
            })
        };
        let mut batches = 0;
        while wait_once(&mut w).is_some() {
            batches += 1;
            if writer.is_finished() {
                // One more batch may be in flight; collect it, then stop.
                while w
                    .wait(Some(Instant::now() + Duration::from_millis(700)), &|| false)
                    .is_some()
                {
                    batches += 1;
                }
                break;
            }
        }
        let times = writer.join().unwrap();
        // The rule: a batch closes after QUIET without an event or MAX_BATCH after its first.
        // So the saves make at most one batch per MAX_BATCH of their span, plus one per pause
        // longer than QUIET (a loaded machine delays the writer), plus the one in flight.
        let span = times[times.len() - 1] - times[0];
        let pauses = times.windows(2).filter(|w| w[1] - w[0] >= QUIET).count();
        let most = (span.as_secs_f64() / MAX_BATCH.as_secs_f64()).ceil() as usize + pauses + 1;
        println!(
            "50 saves over {span:?} ({pauses} pauses over {QUIET:?}) arrived as {batches} \
             batches, at most {most} allowed"
        );
        assert!((1..=most).contains(&batches), "{batches} batches");
        assert!(batches < 50, "not batched: {batches}");
    }

    #[test]
    fn a_missing_directory_is_polled_until_it_appears() {
        let dir = tempfile::tempdir().unwrap();
        let include = dir.path().join("sub").join("inc.scn");
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&include]).unwrap();
        assert_eq!(
            w.wait(Some(Instant::now() + Duration::from_millis(400)), &|| false),
            None
        );
        fs::create_dir(dir.path().join("sub")).unwrap();
        fs::write(&include, "x").unwrap();
        let got = wait_once(&mut w).expect("the new file is reported");
        assert!(got.iter().any(|p| p.ends_with("sub/inc.scn")), "{got:?}");
    }

    #[test]
    fn dropped_dependencies_are_no_longer_reported() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.scn"), dir.path().join("b.scn"));
        fs::write(&a, "1").unwrap();
        fs::write(&b, "1").unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&a, &b]).unwrap();
        w.set_dependencies([&a]).unwrap();
        settle(&mut w);
        fs::write(&b, "2").unwrap();
        assert_eq!(
            w.wait(Some(Instant::now() + Duration::from_millis(500)), &|| false),
            None
        );
        fs::write(&a, "2").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&a)]));
    }

    /// An evaluation reads the files while the old set is still watched; a save during it
    /// (of a file in the old set, or of one only the new set has) is reported by the next wait.
    #[test]
    fn saves_during_an_evaluation_are_kept_across_set_dependencies() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.scn"), dir.path().join("b.scn"));
        fs::write(&a, "1").unwrap();
        fs::write(&b, "1").unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&a]).unwrap();
        settle(&mut w);
        // "Evaluating": the save's events queue up, nobody waits.
        fs::write(&a, "2").unwrap();
        std::thread::sleep(Duration::from_millis(300));
        w.set_dependencies([&a]).unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&a)]));
        fs::write(&b, "2").unwrap();
        std::thread::sleep(Duration::from_millis(300));
        w.set_dependencies([&a, &b]).unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&b)]));
    }

    /// A file in a folder that nothing watched while the evaluation read it: reported when it
    /// was modified after the evaluation began, not when it is older.
    #[test]
    fn a_file_of_a_new_folder_modified_during_the_evaluation_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.scn");
        let (fresh, old) = (dir.path().join("new"), dir.path().join("old"));
        fs::create_dir(&fresh).unwrap();
        fs::create_dir(&old).unwrap();
        let (inc, tex) = (fresh.join("inc.scn"), old.join("tex.png"));
        fs::write(&scene, "1").unwrap();
        fs::write(&tex, "x").unwrap();
        let hour_ago = SystemTime::now() - Duration::from_secs(3600);
        fs::File::options()
            .write(true)
            .open(&tex)
            .unwrap()
            .set_modified(hour_ago)
            .unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([&scene]).unwrap();
        settle(&mut w);
        let began = SystemTime::now();
        fs::write(&inc, "edited after the evaluation read it").unwrap();
        w.set_dependencies_after([&scene, &inc, &tex], began)
            .unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&inc)]));
        // Both folders are watched from now on; nothing else is pending.
        assert_eq!(
            w.wait(Some(Instant::now() + Duration::from_millis(500)), &|| false),
            None
        );
        fs::write(&tex, "y").unwrap();
        assert_eq!(wait_once(&mut w), Some(vec![normalize(&tex)]));
    }

    #[test]
    fn stop_returns_promptly() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = DependencyWatcher::new().unwrap();
        w.set_dependencies([dir.path().join("x.scn")]).unwrap();
        let start = Instant::now();
        assert_eq!(w.wait(None, &|| true), None);
        assert!(start.elapsed() < Duration::from_secs(1));
    }
}
