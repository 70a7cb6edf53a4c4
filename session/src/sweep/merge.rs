//! `ubf sweep merge`: the shards' records and reports read back, checked
//! as the untrusted files they are, and summarised as one sweep.

use super::*;

/// Why shards could not be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A record or report is not what a shard writes.
    #[error("{}: {message}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line and column where JSON knows them.
        message: String,
    },
    /// The shards do not make one whole sweep.
    #[error("{0}")]
    Incomplete(String),
    /// The summary could not be written.
    #[error(transparent)]
    Write(#[from] SweepError),
}

/// The largest shard record [`merge`] reads: a record lists its failed
/// runs, a few hundred bytes each.
pub(super) const MOST_RECORD_BYTES: u64 = 256 << 20;

/// The most missing shards an error lists one by one.
const MOST_MISSING_LISTED: usize = 20;

/// Reads `path` as text, refusing a file larger than `most` bytes before
/// reading it.
fn read_bounded(path: &Path, most: u64) -> Result<String, MergeError> {
    let bytes = ubf_core::config::read_bounded(path, most)
        .map_err(|source| MergeError::Read { path: path.to_owned(), source })?;
    String::from_utf8(bytes)
        .map_err(|_| MergeError::Malformed { path: path.to_owned(), message: "not UTF-8 text".into() })
}

impl ShardRecord {
    /// What is wrong with a record as read from a file, if anything: a
    /// shard of none or outside its count, an empty or reversed range of
    /// seeds, a label that is no safe folder name (`../x`) or given twice,
    /// a failed run that is not this shard's.
    fn check(&self) -> Result<(), String> {
        let Shard { index, count } = self.shard;
        if count == 0 || index >= count {
            return Err(format!("shard {index}/{count}: expected K/N with 0 ≤ K < N"));
        }
        let [start, end] = self.seeds;
        if start >= end {
            return Err(format!("seeds {start}..{end} hold no seed"));
        }
        if self.labels.is_empty() {
            return Err("no scenarios".into());
        }
        for (i, label) in self.labels.iter().enumerate() {
            check_label(label)?;
            if self.labels[..i].contains(label) {
                return Err(format!("the label `{label}` is listed twice"));
            }
        }
        let per_item = usize::try_from(end - start).map_err(|_| format!("seeds {start}..{end}: too many"))?;
        per_item.checked_mul(self.labels.len()).ok_or_else(|| format!("seeds {start}..{end}: too many runs"))?;
        for (label, seed, _) in &self.failed {
            let position = self.labels.iter().position(|l| l == label);
            let task = position.filter(|_| (start..end).contains(seed)).map(|i| i * per_item + (seed - start) as usize);
            if !task.is_some_and(|task| self.shard.takes(task)) {
                return Err(format!("failed run {label} seed {seed} is not one of this shard's runs"));
            }
        }
        Ok(())
    }
}

/// Merges the shards recorded in `dirs` (each holding one or more
/// `shard-K-of-N.json` and those shards' runs) into the summary one sweep
/// would have written, and writes `summary.csv` and `summary.json` into
/// `out`. Refuses shards of different sweeps, a shard twice, a missing
/// one, and a record that is not what a shard writes (each error names
/// the file). Reads only under `dirs` and writes only into `out`: labels
/// are checked ([`check_label`]) before any path is made of them, and no
/// number read from a file sizes an allocation.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<SweepSummary, MergeError> {
    let mut records: Vec<(PathBuf, PathBuf, ShardRecord)> = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(dir).map_err(|source| MergeError::Read { path: dir.clone(), source })?;
        let mut names: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("shard-") && n.ends_with(".json"))
            })
            .collect();
        names.sort();
        for path in names {
            let text = read_bounded(&path, MOST_RECORD_BYTES)?;
            let malformed = |message: String| MergeError::Malformed { path: path.clone(), message };
            let record: ShardRecord = serde_json::from_str(&text).map_err(|e| malformed(e.to_string()))?;
            record.check().map_err(malformed)?;
            records.push((dir.clone(), path, record));
        }
    }
    let Some((_, _, first)) = records.first() else {
        let shown: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        return Err(MergeError::Incomplete(format!("no shard records (shard-K-of-N.json) in {}", shown.join(", "))));
    };
    let (seeds, labels, count) = (first.seeds, first.labels.clone(), first.shard.count);
    let mut owner: BTreeMap<u64, usize> = BTreeMap::new();
    for (n, (_, path, record)) in records.iter().enumerate() {
        if record.seeds != seeds || record.labels != labels || record.shard.count != count {
            return Err(MergeError::Incomplete(format!(
                "{}: {} belongs to another sweep (seeds {:?}, scenarios {:?}, {} shards; expected {:?}, {:?}, {count})",
                path.display(),
                record.shard.record_name(),
                record.seeds,
                record.labels,
                record.shard.count,
                seeds,
                labels
            )));
        }
        if owner.insert(record.shard.index, n).is_some() {
            return Err(MergeError::Incomplete(format!(
                "shard {}/{count} is recorded twice ({} again)",
                record.shard.index,
                path.display()
            )));
        }
    }
    // Every index is below the count and none twice: as many records as
    // shards means none is missing.
    let missing_count = count - owner.len() as u64;
    if missing_count > 0 {
        let listed: Vec<String> = (0..count)
            .filter(|k| !owner.contains_key(k))
            .take(MOST_MISSING_LISTED)
            .map(|k| format!("{k}/{count}"))
            .collect();
        let more = missing_count - listed.len() as u64;
        let more = if more > 0 { format!(" and {more} more") } else { String::new() };
        return Err(MergeError::Incomplete(format!("missing shards: {}{more}", listed.join(", "))));
    }
    let range = seeds[0]..seeds[1];
    let per_item = (seeds[1] - seeds[0]) as usize;
    // Read every run's report first, so that a broken one is an error, not
    // a failed run. No capacity is reserved: the records say how many runs
    // there are, and only the files read back say it truly.
    let mut outcomes: Vec<Result<Vec<(String, f64)>, String>> = Vec::new();
    for task in 0..labels.len() * per_item {
        let (label, seed) = (&labels[task / per_item], seeds[0] + (task % per_item) as u64);
        let (dir, _, record) = &records[owner[&(task as u64 % count)]];
        if let Some((_, _, error)) = record.failed.iter().find(|(l, s, _)| l == label && *s == seed) {
            outcomes.push(Err(error.clone()));
            continue;
        }
        let path = dir.join(label).join(seed_folder(seed)).join("report.json");
        let text = read_bounded(&path, super::MOST_REPORT_BYTES)?;
        let report: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| MergeError::Malformed { path: path.clone(), message: e.to_string() })?;
        outcomes.push(Ok(numeric_leaves(&report)));
    }
    let summary = summarise(&labels, range, |task| outcomes[task].clone());
    write_summary(&summary, out)?;
    Ok(summary)
}
