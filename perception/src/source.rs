//! Where stereo pairs come from, behind one trait: a directory of recorded
//! or rendered pairs (replay), the simulator's renderer (in `ubf-robots`),
//! a camera on the robot.
//!
//! A directory holds `frames.csv`, one line per pair after a header:
//!
//! ```text
//! time_s,left,right
//! 0.000,left/000001.png,right/000001.png
//! 0.500,left/000002.png,right/000002.png
//! ```
//!
//! Paths are relative to the directory; images are 8-bit grey PNGs,
//! rectified, of the size the calibration says.

use image::GrayImage;
use std::fs;
use std::io::{self, BufRead, Write};
use std::path::{Path, PathBuf};

/// A rectified stereo pair and when it was taken.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoPair {
    /// Seconds from the source's start.
    pub time: f64,
    /// The left image.
    pub left: GrayImage,
    /// The right image.
    pub right: GrayImage,
}

impl StereoPair {
    /// The pair's pixels, moved (not copied) into the shape frames carry.
    pub fn into_images(self) -> ubf_core::StereoImages {
        let (width, height) = self.left.dimensions();
        ubf_core::StereoImages { width, height, left: self.left.into_raw(), right: self.right.into_raw() }
    }

    /// A frame's pixels as a pair taken at `time` (copied); `None` if the
    /// buffers do not hold `width × height` pixels.
    pub fn from_images(time: f64, images: &ubf_core::StereoImages) -> Option<StereoPair> {
        let image = |pixels: &Vec<u8>| GrayImage::from_raw(images.width, images.height, pixels.clone());
        Some(StereoPair { time, left: image(&images.left)?, right: image(&images.right)? })
    }
}

/// What went wrong reading or writing pairs.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// An image could not be decoded or encoded.
    #[error("{path}: {message}")]
    Image {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A line of an index (`frames.csv`, a KITTI sequence's text files) is
    /// not what it should be.
    #[error("{path}:{line}: {message}")]
    Index {
        /// The index file.
        path: PathBuf,
        /// Its line, from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An image a line of an index lists could not be read.
    #[error("{index}:{line}: {source}")]
    Listed {
        /// The index file.
        index: PathBuf,
        /// The line that lists the image, from 1.
        line: usize,
        /// Why the image could not be read.
        source: Box<SourceError>,
    },
}

/// A source of stereo pairs.
pub trait CameraSource {
    /// The next pair, or `None` when there are no more.
    fn next_pair(&mut self) -> Result<Option<StereoPair>, SourceError>;
}

impl<S: CameraSource + ?Sized> CameraSource for Box<S> {
    fn next_pair(&mut self) -> Result<Option<StereoPair>, SourceError> {
        (**self).next_pair()
    }
}

/// One pair listed in a directory's index: its time and where its two
/// image names lie in [`ImageDirectory::names`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    time: f64,
    line: u32,
    left_end: u32,
    right_end: u32,
}

/// Replays a directory of pairs in the order of its index.
///
/// The index is held compactly (the names of every pair in one string, and
/// 16 bytes a pair besides), so a long recording's index costs about its
/// own size in memory.
#[derive(Clone, Debug)]
pub struct ImageDirectory {
    dir: PathBuf,
    /// The file that lists the pairs, for errors.
    index: PathBuf,
    names: String,
    entries: Vec<Entry>,
    next: usize,
}

/// The index file's name.
const INDEX: &str = "frames.csv";

impl ImageDirectory {
    /// Reads the index of `dir`; images are read as they are asked for.
    pub fn open(dir: &Path) -> Result<ImageDirectory, SourceError> {
        let path = dir.join(INDEX);
        let io_error = |source| SourceError::Io { path: path.clone(), source };
        let reader = io::BufReader::new(fs::File::open(&path).map_err(io_error)?);
        let mut listing = ImageDirectory::empty(dir, &path);
        for (number, line) in reader.lines().enumerate() {
            let bad = |message: String| SourceError::Index { path: path.clone(), line: number + 1, message };
            let line = line.map_err(|e| bad(e.to_string()))?;
            if number == 0 || line.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let [time, left, right] = fields[..] else {
                return Err(bad(format!("expected time_s,left,right; got {} fields", fields.len())));
            };
            let time: f64 = time.parse().map_err(|_| bad(format!("time {time:?} is not a number")))?;
            listing.push(time, number + 1, left, right).map_err(bad)?;
        }
        Ok(listing)
    }

    /// A listing of no pairs yet, of images relative to `dir`, listed by
    /// the file `index`.
    pub(crate) fn empty(dir: &Path, index: &Path) -> ImageDirectory {
        ImageDirectory {
            dir: dir.to_owned(),
            index: index.to_owned(),
            names: String::new(),
            entries: Vec::new(),
            next: 0,
        }
    }

    /// Lists a pair, from line `line` of the index.
    pub(crate) fn push(&mut self, time: f64, line: usize, left: &str, right: &str) -> Result<(), String> {
        if !time.is_finite() || self.entries.last().is_some_and(|e| time < e.time) {
            return Err(format!("time {time} is not finite and non-decreasing"));
        }
        let too_long = || "the index passes 4 GB or 4 billion lines".to_owned();
        let line = u32::try_from(line).map_err(|_| too_long())?;
        self.names.push_str(left);
        let left_end = u32::try_from(self.names.len()).map_err(|_| too_long())?;
        self.names.push_str(right);
        let right_end = u32::try_from(self.names.len()).map_err(|_| too_long())?;
        self.entries.push(Entry { time, line, left_end, right_end });
        Ok(())
    }

    /// How many pairs the directory lists.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether it lists none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The paths of pair `i`'s two images.
    fn paths(&self, i: usize) -> (PathBuf, PathBuf) {
        let start = if i == 0 { 0 } else { self.entries[i - 1].right_end as usize };
        let Entry { left_end, right_end, .. } = self.entries[i];
        let (left, right) = (&self.names[start..left_end as usize], &self.names[left_end as usize..right_end as usize]);
        (self.dir.join(left), self.dir.join(right))
    }
}

/// A reader of the image at `path`, its format told by its name. A FIFO
/// or a device in the image's place is refused rather than waited on.
pub(crate) fn open_image(path: &Path) -> Result<image::ImageReader<io::BufReader<fs::File>>, SourceError> {
    let file =
        ubf_core::config::open_regular(path).map_err(|source| SourceError::Io { path: path.to_owned(), source })?;
    let format = image::ImageFormat::from_path(path)
        .map_err(|e| SourceError::Image { path: path.to_owned(), message: e.to_string() })?;
    Ok(image::ImageReader::with_format(io::BufReader::new(file), format))
}

/// The image at `path` in grey levels.
pub(crate) fn read_grey(path: &Path) -> Result<GrayImage, SourceError> {
    let image = open_image(path)?.decode().map_err(|e| match e {
        image::ImageError::IoError(source) => SourceError::Io { path: path.to_owned(), source },
        other => SourceError::Image { path: path.to_owned(), message: other.to_string() },
    })?;
    Ok(image.into_luma8())
}

impl CameraSource for ImageDirectory {
    fn next_pair(&mut self) -> Result<Option<StereoPair>, SourceError> {
        let Some(&entry) = self.entries.get(self.next) else { return Ok(None) };
        let (left, right) = self.paths(self.next);
        self.next += 1;
        let listed = |source| SourceError::Listed {
            index: self.index.clone(),
            line: entry.line as usize,
            source: Box::new(source),
        };
        Ok(Some(StereoPair {
            time: entry.time,
            left: read_grey(&left).map_err(listed)?,
            right: read_grey(&right).map_err(listed)?,
        }))
    }
}

/// Writes pairs into a directory that [`ImageDirectory`] replays.
#[derive(Debug)]
pub struct ImageDirectoryWriter {
    dir: PathBuf,
    index: io::BufWriter<fs::File>,
    count: usize,
}

impl ImageDirectoryWriter {
    /// Creates `dir` (and its `left/`, `right/`) and its index.
    pub fn create(dir: &Path) -> Result<ImageDirectoryWriter, SourceError> {
        let io_error = |path: &Path| {
            let path = path.to_owned();
            move |source| SourceError::Io { path, source }
        };
        for sub in ["left", "right"] {
            fs::create_dir_all(dir.join(sub)).map_err(io_error(&dir.join(sub)))?;
        }
        let path = dir.join(INDEX);
        let mut index = io::BufWriter::new(fs::File::create(&path).map_err(io_error(&path))?);
        writeln!(index, "time_s,left,right").map_err(io_error(&path))?;
        Ok(ImageDirectoryWriter { dir: dir.to_owned(), index, count: 0 })
    }

    /// Adds a pair.
    pub fn push(&mut self, pair: &StereoPair) -> Result<(), SourceError> {
        self.count += 1;
        let names = [format!("left/{:06}.png", self.count), format!("right/{:06}.png", self.count)];
        for (name, image) in names.iter().zip([&pair.left, &pair.right]) {
            let path = self.dir.join(name);
            image.save(&path).map_err(|e| SourceError::Image { path, message: e.to_string() })?;
        }
        let path = self.dir.join(INDEX);
        writeln!(self.index, "{:.3},{},{}", pair.time, names[0], names[1])
            .map_err(|source| SourceError::Io { path, source })
    }

    /// Flushes the index; the pairs written so far are complete.
    pub fn finish(mut self) -> Result<usize, SourceError> {
        let path = self.dir.join(INDEX);
        self.index.flush().map_err(|source| SourceError::Io { path, source })?;
        Ok(self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_fifo_in_an_image_s_place_is_refused_not_waited_on() {
        let path = std::env::temp_dir().join(format!("ubf-source-fifo-{}.png", std::process::id()));
        let _ = fs::remove_file(&path);
        assert!(std::process::Command::new("mkfifo").arg(&path).status().unwrap().success());
        let (sent, read) = std::sync::mpsc::channel();
        let fifo = path.clone();
        std::thread::spawn(move || sent.send(read_grey(&fifo).map(drop).map_err(|e| e.to_string())));
        let outcome = read.recv_timeout(std::time::Duration::from_secs(10));
        fs::remove_file(&path).unwrap();
        let said = outcome.expect("reading the image waited for a writer").unwrap_err();
        assert!(said.ends_with("not a regular file"), "{said}");
    }

    #[test]
    fn pairs_written_are_replayed_in_order() {
        let dir = std::env::temp_dir().join(format!("ubf-source-{}", std::process::id()));
        let pair = |t: f64, v: u8| StereoPair {
            time: t,
            left: GrayImage::from_pixel(8, 6, image::Luma([v])),
            right: GrayImage::from_pixel(8, 6, image::Luma([v + 1])),
        };
        let mut writer = ImageDirectoryWriter::create(&dir).unwrap();
        writer.push(&pair(0.0, 10)).unwrap();
        writer.push(&pair(0.5, 20)).unwrap();
        assert_eq!(writer.finish().unwrap(), 2);
        let mut source = ImageDirectory::open(&dir).unwrap();
        assert_eq!(source.len(), 2);
        assert_eq!(source.next_pair().unwrap(), Some(pair(0.0, 10)));
        assert_eq!(source.next_pair().unwrap(), Some(pair(0.5, 20)));
        assert_eq!(source.next_pair().unwrap(), None);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_indexes_and_missing_images_are_reported_with_their_place() {
        let dir = std::env::temp_dir().join(format!("ubf-source-bad-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let open_with = |text: &str| {
            fs::write(dir.join(INDEX), text).unwrap();
            ImageDirectory::open(&dir)
        };
        let err = open_with("time_s,left,right\n0.0,a.png\n").unwrap_err().to_string();
        assert!(err.ends_with("frames.csv:2: expected time_s,left,right; got 2 fields"), "{err}");
        let err = open_with("time_s,left,right\n1.0,a.png,b.png\n0.5,a.png,b.png\n").unwrap_err().to_string();
        assert!(err.contains("frames.csv:3: time 0.5"), "{err}");
        let err = open_with("h\nsoon,a.png,b.png\n").unwrap_err().to_string();
        assert!(err.contains(":2: time \"soon\""), "{err}");
        let mut source = open_with("h\n0,missing.png,b.png\n").unwrap();
        let err = source.next_pair().unwrap_err().to_string();
        assert!(err.contains("frames.csv:2: ") && err.contains("missing.png"), "{err}");
        fs::write(dir.join("junk.png"), b"not a png").unwrap();
        let mut source = open_with("h\n0,junk.png,junk.png\n").unwrap();
        let err = source.next_pair().unwrap_err();
        assert!(matches!(&err, SourceError::Listed { source, .. } if matches!(**source, SourceError::Image { .. })));
        let _ = fs::remove_dir_all(&dir);
    }
}
