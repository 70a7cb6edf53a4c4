//! `--watch`: a scenario or robot file edited while it runs. Each edit is
//! checked as the file would be at the start; a valid tree is swapped in at
//! the next tick boundary, and anything else is refused with its reason
//! while the running tree goes on.
//!
//! Only the tree (`root`) changes while running. An edit to anything else
//! (the robot's connection or model, the world, the goal, the safety
//! settings) is refused as a whole, naming the fields, because applying it
//! needs a restart and applying half an edit would surprise.
//!
//! The file is looked at a few times a second from the tick loop: a
//! `stat`, and a read and parse only when it changed. Polling is enough for
//! one file and survives editors that save by renaming a new file over the
//! old one.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};
use ubf_core::{Behavior, BehaviorSpec, BuildContext, TreeSource};

/// How often the file is looked at.
const LOOK_EVERY: Duration = Duration::from_millis(250);

/// Reads a file's tree, checked as at the start: the tree, or why not as a
/// sentence naming the file (and line and column where there is one).
pub type LoadTree = Box<dyn FnMut(&Path) -> Result<BehaviorSpec, String>>;

/// A file watched for a new tree.
pub struct TreeWatch {
    path: PathBuf,
    /// The file's size and time of change as last looked at.
    stamp: Option<Stamp>,
    /// The file's bytes as last read.
    bytes: Vec<u8>,
    /// What the file says besides its tree, as when the session began.
    settings: Option<Settings>,
    /// The tree running now: the file's at the start, or its last edit
    /// taken.
    current: BehaviorSpec,
    context: BuildContext,
    next_look: Instant,
    load: LoadTree,
}

impl TreeWatch {
    /// Watches `path`, whose tree `current` runs now, built in `context`,
    /// reading new trees with `load`.
    pub fn new(path: &Path, current: BehaviorSpec, context: BuildContext, load: LoadTree) -> TreeWatch {
        let stamp = stamp_of(path).and_then(settled);
        let bytes = read(path).unwrap_or_default();
        let settings = settings_of(&bytes);
        let next_look = Instant::now() + LOOK_EVERY;
        TreeWatch { path: path.to_owned(), stamp, bytes, settings, current, context, next_look, load }
    }

    /// The tree running now: what a new session (a drive that reconnected)
    /// starts with.
    pub fn current(&self) -> &BehaviorSpec {
        &self.current
    }

    /// The new tree in the file, if it changed and holds a valid one and
    /// nothing else changed; says on stderr what it did with the edit.
    fn look(&mut self) -> Option<Box<dyn Behavior>> {
        // Read only once the file has changed, and only a regular file of a
        // settings file's size: this runs in the tick loop, which a FIFO put
        // in the file's place would block, or /dev/zero fill memory.
        let stamp = stamp_of(&self.path)?;
        if self.stamp == Some(stamp) {
            return None;
        }
        let bytes = match read(&self.path) {
            Ok(bytes) => bytes,
            Err(e) => {
                // Said once per change, and looked at again at the next.
                self.stamp = Some(stamp);
                eprintln!("{}: {e}: edit refused; the running tree goes on", self.path.display());
                return None;
            }
        };
        self.stamp = settled(stamp);
        if bytes == self.bytes {
            return None;
        }
        self.bytes = bytes;
        let file = self.path.display();
        // A file that does not parse is refused here, with its place.
        let tree = match (self.load)(&self.path) {
            Ok(tree) => tree,
            Err(why) => {
                eprintln!("{why}\n{file}: edit refused; the running tree goes on");
                return None;
            }
        };
        let changed = changed_fields(self.settings.as_ref(), settings_of(&self.bytes).as_ref());
        if !changed.is_empty() {
            eprintln!(
                "{file}: {} changed; only the tree (`root`) changes while running, so the edit is refused and the \
                 running tree goes on: restart to apply it",
                changed.join(", ")
            );
            return None;
        }
        eprintln!("{file}: edited; the new tree runs from the next tick");
        let built = tree.build(&self.context);
        self.current = tree;
        Some(built)
    }

    /// This watch as a [`TreeSource`] for one session, kept by the caller
    /// for the next (a drive's sessions share one watch).
    pub fn shared(self) -> SharedTreeWatch {
        SharedTreeWatch(Rc::new(RefCell::new(self)))
    }
}

impl TreeSource for TreeWatch {
    fn next_tree(&mut self) -> Option<Box<dyn Behavior>> {
        let now = Instant::now();
        if now < self.next_look {
            return None;
        }
        self.next_look = now + LOOK_EVERY;
        self.look()
    }
}

/// A [`TreeWatch`] that outlives the sessions it serves.
#[derive(Clone)]
pub struct SharedTreeWatch(Rc<RefCell<TreeWatch>>);

impl SharedTreeWatch {
    /// The tree running now.
    pub fn current(&self) -> BehaviorSpec {
        self.0.borrow().current().clone()
    }
}

impl TreeSource for SharedTreeWatch {
    fn next_tree(&mut self) -> Option<Box<dyn Behavior>> {
        self.0.borrow_mut().next_tree()
    }
}

/// What tells a file's edit without reading it: its size, when its content
/// and when its inode last changed (a copy that keeps the time, a chmod),
/// and which file it is (a rename over it).
type Stamp = (u64, std::time::SystemTime, (i64, i64), (u64, u64));

/// `path`'s stamp (whatever it is: a FIFO put in its place is refused
/// once, not opened).
fn stamp_of(path: &Path) -> Option<Stamp> {
    use std::os::unix::fs::MetadataExt;
    let metadata = std::fs::metadata(path).ok()?;
    let changed = (metadata.ctime(), metadata.ctime_nsec());
    Some((metadata.len(), metadata.modified().ok()?, changed, (metadata.dev(), metadata.ino())))
}

/// `stamp`, if it tells the file's next edit: a file changed within the
/// coarsest step a file system stamps times in may change again within
/// that step, keeping its size and times, so until then it is read at
/// every look.
fn settled(stamp: Stamp) -> Option<Stamp> {
    let age = std::time::SystemTime::now().duration_since(stamp.1).unwrap_or_default();
    (age > COARSEST_TIMESTAMP_STEP).then_some(stamp)
}

/// FAT's, on the USB stick a scenario may be edited on: 2 s (ext4 and
/// most others stamp to the nanosecond, HFS+ to the second).
const COARSEST_TIMESTAMP_STEP: Duration = Duration::from_secs(2);

/// `path`'s bytes, if it is a regular file of a settings file's size.
fn read(path: &Path) -> std::io::Result<Vec<u8>> {
    ubf_core::config::read_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES)
}

/// A file's fields other than its tree, each as its RON text (comments and
/// spacing at its ends aside), or `None` if it is no RON structure. Text,
/// because RON's own `Value` reads every enum variant as `()` and would
/// miss `model: Powerbot` becoming `model: P3dx`.
fn settings_of(bytes: &[u8]) -> Option<Settings> {
    let text = std::str::from_utf8(bytes).ok()?;
    let Fields(mut fields) = ubf_core::config::from_ron::<Fields>(text).ok()?;
    fields.remove("root");
    Some(fields)
}

/// A structure's fields, by name, as RON text.
type Settings = BTreeMap<String, String>;

/// What [`settings_of`] reads: any RON structure, named or not.
struct Fields(Settings);

impl<'de> serde::Deserialize<'de> for Fields {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Fields, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Fields;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a structure")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Fields, A::Error> {
                let mut fields = Settings::new();
                while let Some(name) = map.next_key::<String>()? {
                    let value: Box<ron::value::RawValue> = map.next_value()?;
                    fields.insert(name, value.get_ron().trim().to_owned());
                }
                Ok(Fields(fields))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// The names of the fields that differ between `before` and `after`.
fn changed_fields(before: Option<&Settings>, after: Option<&Settings>) -> Vec<String> {
    let (Some(before), Some(after)) = (before, after) else {
        return if before == after { Vec::new() } else { vec!["the file's structure".into()] };
    };
    let mut names: Vec<String> = before
        .keys()
        .chain(after.keys())
        .filter(|name| before.get(*name) != after.get(*name))
        .map(|name| format!("`{name}`"))
        .collect();
    names.sort();
    names.dedup();
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(text: &str) -> Option<Settings> {
        settings_of(text.as_bytes())
    }

    #[test]
    fn only_fields_besides_the_tree_count_as_changed() {
        let before = fields("Robot(connection: \"tcp://a:1\", model: Powerbot, root: Stop())");
        let tree_only = fields("Robot(connection: \"tcp://a:1\", model: Powerbot, root: GoTo())");
        let moved = fields("Robot(connection: \"tcp://b:1\", model: P3dx, root: Stop())");
        assert!(changed_fields(before.as_ref(), tree_only.as_ref()).is_empty());
        assert_eq!(changed_fields(before.as_ref(), moved.as_ref()), ["`connection`", "`model`"]);
        let added = fields("Robot(connection: \"tcp://a:1\", model: Powerbot, goal: (x: 1.0), root: Stop())");
        assert_eq!(changed_fields(before.as_ref(), added.as_ref()), ["`goal`"]);
    }

    #[test]
    fn a_stamp_within_fats_two_seconds_is_not_settled() {
        // On FAT a second edit 1.5 s after the first can keep the size and
        // every time the stamp holds (ctime is mtime there), and would be
        // missed for good had the first been taken as settled.
        let now = std::time::SystemTime::now();
        let stamp = |age: f64| (10, now - Duration::from_secs_f64(age), (0, 0), (0, 0));
        assert_eq!(settled(stamp(1.5)), None);
        assert_eq!(settled(stamp(2.5)), Some(stamp(2.5)));
    }

    #[test]
    fn an_edit_is_taken_once_and_a_bad_one_is_refused() {
        #[derive(serde::Deserialize)]
        struct Robot {
            root: BehaviorSpec,
        }
        let registry = crate::registry();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tree.ron");
        std::fs::write(&path, "(model: Powerbot, root: Stop())").unwrap();
        let reader = registry.clone();
        let load: LoadTree = Box::new(move |path| {
            let text = std::fs::read_to_string(path).unwrap();
            let robot: Robot = reader.from_ron(&text).map_err(|e| format!("{}: {e}", path.display()))?;
            Ok(robot.root)
        });
        let start: Robot = registry.from_ron("(root: Stop())").unwrap();
        let mut watch = TreeWatch::new(&path, start.root, BuildContext::new(0), load);
        assert!(watch.look().is_none(), "nothing changed");
        std::fs::write(&path, "(model: Powerbot, root: GoTo())").unwrap();
        assert_eq!(watch.look().map(|t| t.name().to_owned()).as_deref(), Some("GoTo"));
        assert!(watch.look().is_none(), "an edit is taken once");
        std::fs::write(&path, "(model: Powerbot, root: NoSuchBehaviour())").unwrap();
        assert!(watch.look().is_none(), "a bad edit is refused");
        std::fs::write(&path, "(model: P3dx, root: Stop())").unwrap();
        assert!(watch.look().is_none(), "an edit beyond the tree is refused");
        assert_eq!(watch.current().kind(), "GoTo", "the last edit taken runs");
        // A file put in its place with the same size and an old time kept
        // (`cp -p`, an archive) is still an edit.
        let old = std::time::UNIX_EPOCH + Duration::from_secs(1_000_000_000);
        let write_old = |at: &Path, text: &str| {
            std::fs::write(at, text).unwrap();
            std::fs::File::options().write(true).open(at).unwrap().set_modified(old).unwrap();
        };
        write_old(&path, "(model: Powerbot, root: Stop())");
        assert_eq!(watch.look().map(|t| t.name().to_owned()).as_deref(), Some("Stop"));
        let copy = dir.path().join("copy.ron");
        write_old(&copy, "(model: Powerbot, root: GoTo())");
        std::fs::rename(&copy, &path).unwrap();
        assert_eq!(watch.look().map(|t| t.name().to_owned()).as_deref(), Some("GoTo"));
        // A FIFO in the file's place is not opened (which would block until
        // a writer came), nor is a device read.
        std::fs::remove_file(&path).unwrap();
        let made = std::process::Command::new("mkfifo").arg(&path).status().unwrap();
        assert!(made.success());
        assert!(watch.look().is_none());
        std::fs::remove_file(&path).unwrap();
        std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
        assert!(watch.look().is_none());
    }
}
