//! `--shard`: a sweep's share given as `K/N`, or taken from the job array
//! or indexed job the sweep runs in (`auto`, `auto/N`), so that one job
//! script serves every task.

use super::CliError;
use crate::sweep::Shard;

/// What `--shard` says: the share itself, or where to find it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ShardSpec {
    /// `K/N`: share K of N.
    Given(Shard),
    /// `auto`: from a Slurm job array's `SLURM_ARRAY_TASK_*` variables.
    Slurm,
    /// `auto/N`: share `JOB_COMPLETION_INDEX` of N, as a Kubernetes Indexed
    /// Job numbers its pods (it does not tell them how many there are).
    Indexed {
        /// How many shares: the Job's `completions`.
        count: u64,
    },
}

impl ShardSpec {
    /// Reads `K/N` (0 ≤ K < N), `auto` or `auto/N` (N ≥ 1).
    pub(super) fn parse(text: &str) -> Result<ShardSpec, String> {
        if text == "auto" {
            return Ok(ShardSpec::Slurm);
        }
        if let Some(count) = text.strip_prefix("auto/") {
            return match count.parse::<u64>() {
                Ok(count) if count > 0 => Ok(ShardSpec::Indexed { count }),
                _ => Err(format!("`auto/N` needs a number of shards N ≥ 1 (the Job's completions); got {text:?}")),
            };
        }
        Shard::parse(text).map(ShardSpec::Given).map_err(|_| {
            format!(
                "expected K/N with 0 ≤ K < N (shards are numbered from 0, e.g. 0/8), `auto` in a Slurm job array, \
                 or `auto/N` in a Kubernetes Indexed Job of N completions; got {text:?}"
            )
        })
    }
}

/// The shard `spec` names, with a line saying which variables it came
/// from (none for `K/N`). `var` looks a variable up, so that this reads
/// the process's environment, or a test's.
pub(super) fn resolve(
    spec: ShardSpec,
    var: impl Fn(&str) -> Option<String>,
) -> Result<(Shard, Option<String>), String> {
    match spec {
        ShardSpec::Given(shard) => Ok((shard, None)),
        ShardSpec::Slurm => from_slurm(&var).map(|(shard, from)| (shard, Some(from))),
        ShardSpec::Indexed { count } => from_indexed_job(&var, count).map(|(shard, from)| (shard, Some(from))),
    }
}

/// [`resolve`] in this process's environment, saying on stderr where an
/// `auto` shard came from: the one line that tells a job's log which share
/// it ran.
pub(super) fn resolve_here(spec: ShardSpec) -> Result<Shard, CliError> {
    let var = |name: &str| std::env::var_os(name).map(|v| v.to_string_lossy().into_owned());
    let (shard, from) = resolve(spec, var).map_err(CliError::bad_input)?;
    if let Some(from) = from {
        eprintln!("{from}");
    }
    Ok(shard)
}

/// `name`'s value as a whole number, `None` if it is not set; `setter`
/// is who sets it (Slurm, Kubernetes).
fn number(var: &impl Fn(&str) -> Option<String>, name: &str, setter: &str) -> Result<Option<u64>, String> {
    let Some(value) = var(name) else { return Ok(None) };
    // Digits only: Rust would read `+3` too, which no scheduler writes.
    let digits = !value.is_empty() && value.bytes().all(|b| b.is_ascii_digit());
    match value.parse::<u64>() {
        Ok(n) if digits => Ok(Some(n)),
        _ => Err(format!(
            "{name}={value:?} is not a whole number ≥ 0, and {setter} sets it to one; find what else set it, or give \
             the shard as --shard K/N"
        )),
    }
}

const TASK_ID: &str = "SLURM_ARRAY_TASK_ID";
const TASK_COUNT: &str = "SLURM_ARRAY_TASK_COUNT";
const TASK_MIN: &str = "SLURM_ARRAY_TASK_MIN";
const TASK_MAX: &str = "SLURM_ARRAY_TASK_MAX";
const TASK_STEP: &str = "SLURM_ARRAY_TASK_STEP";
const COMPLETION_INDEX: &str = "JOB_COMPLETION_INDEX";

/// The shard of a Slurm array task: its id less the array's lowest id (an
/// array may start at 1, or anywhere), of as many shards as the array has
/// tasks. Only a contiguous range of ids numbers the shards without gaps.
fn from_slurm(var: &impl Fn(&str) -> Option<String>) -> Result<(Shard, String), String> {
    let slurm = "Slurm in a job array";
    let Some(id) = number(var, TASK_ID, slurm)? else {
        let hint = if var(COMPLETION_INDEX).is_some() {
            format!(
                "{COMPLETION_INDEX} is, so this looks like a Kubernetes Indexed Job: give it the number of shards, \
                 --shard auto/N with N its completions"
            )
        } else {
            "submit the job as an array (sbatch --array=0-99 for 100 shards), or give the shard as --shard K/N"
                .to_owned()
        };
        return Err(format!("--shard auto takes the shard from a Slurm job array, but {TASK_ID} is not set; {hint}"));
    };
    let Some(count) = number(var, TASK_COUNT, slurm)? else {
        return Err(format!(
            "{TASK_ID}={id} is set but {TASK_COUNT} is not, so the number of shards is unknown; Slurm sets both \
             in a job array, so run it as an array task, or give the shard as --shard K/N"
        ));
    };
    let min = number(var, TASK_MIN, slurm)?;
    let max = number(var, TASK_MAX, slurm)?;
    if let Some(step) = number(var, TASK_STEP, slurm)?.filter(|&step| step > 1) {
        return Err(format!(
            "{TASK_STEP}={step}: the array's ids go in steps (--array=0-10:2), so they cannot number shards \
             without gaps; submit a contiguous range, such as --array=0-{}",
            count.saturating_sub(1)
        ));
    }
    if let (Some(min), Some(max)) = (min, max) {
        if max < min || max - min + 1 != count {
            return Err(format!(
                "{TASK_MIN}={min}, {TASK_MAX}={max} and {TASK_COUNT}={count} are not a contiguous range of ids \
                 (the array lists ids, --array=1,3,7, or goes in steps); submit a contiguous range, such as \
                 --array=0-{}",
                count.saturating_sub(1)
            ));
        }
    }
    let no_shard = |why: String| {
        format!(
            "{why}, so it names no shard: these are not one Slurm job array's variables; run it as a task of an \
             array, or give the shard as --shard K/N"
        )
    };
    let Some(index) = id.checked_sub(min.unwrap_or(0)) else {
        return Err(no_shard(format!("{TASK_ID}={id} is below {TASK_MIN}={}", min.unwrap_or(0))));
    };
    // The id as it numbers the shard, for the error and for the job's log.
    let named = match min {
        Some(min) => format!("{TASK_ID}={id} less {TASK_MIN}={min}"),
        None => format!("{TASK_ID}={id}"),
    };
    if index >= count {
        return Err(no_shard(format!("{named} is not below {TASK_COUNT}={count}")));
    }
    Ok((Shard { index, count }, format!("--shard auto: shard {index}/{count}, from {named}, of {TASK_COUNT}={count}")))
}

/// The shard of a Kubernetes Indexed Job's pod: its completion index, of
/// `count` shards.
fn from_indexed_job(var: &impl Fn(&str) -> Option<String>, count: u64) -> Result<(Shard, String), String> {
    let Some(index) = number(var, COMPLETION_INDEX, "Kubernetes in an Indexed Job")? else {
        return Err(format!(
            "--shard auto/{count} takes the shard from a Kubernetes Indexed Job, but {COMPLETION_INDEX} is not \
             set; run it in a Job with completionMode: Indexed (which sets it in every pod), use --shard auto in a \
             Slurm job array, or give the shard as --shard K/N"
        ));
    };
    if index >= count {
        return Err(format!(
            "{COMPLETION_INDEX}={index} is not below the {count} shards of --shard auto/{count}, so the Job has \
             more completions than that; give N as the Job's completions"
        ));
    }
    Ok((
        Shard { index, count },
        format!("--shard auto/{count}: shard {index}/{count}, from {COMPLETION_INDEX}={index}"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Variables by name, as a scheduler would set them.
    type Vars<'a> = &'a [(&'a str, &'a str)];

    /// `vars` as the lookup [`resolve`] takes.
    fn lookup<'a>(vars: Vars<'a>) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| vars.iter().find(|(n, _)| *n == name).map(|(_, v)| (*v).to_owned())
    }

    /// The shard `spec` names among `vars`, or the sentence refusing it.
    fn shard_in(spec: &str, vars: Vars) -> Result<(u64, u64), String> {
        let (shard, _) = resolve(ShardSpec::parse(spec)?, lookup(vars))?;
        Ok((shard.index, shard.count))
    }

    fn refused(spec: &str, vars: Vars) -> String {
        shard_in(spec, vars).expect_err("refused")
    }

    #[test]
    fn a_slurm_array_numbers_its_shards_from_its_lowest_id() {
        let from_one = |id| [(TASK_ID, id), (TASK_MIN, "1"), (TASK_MAX, "4"), (TASK_COUNT, "4"), (TASK_STEP, "1")];
        assert_eq!(shard_in("auto", &from_one("1")), Ok((0, 4)));
        assert_eq!(shard_in("auto", &from_one("4")), Ok((3, 4)));
        // Without the bounds, the ids are taken as they are, from 0.
        assert_eq!(shard_in("auto", &[(TASK_ID, "2"), (TASK_COUNT, "3")]), Ok((2, 3)));
        let (_, from) = resolve(ShardSpec::Slurm, lookup(&from_one("3"))).unwrap();
        let said = "--shard auto: shard 2/4, from SLURM_ARRAY_TASK_ID=3 less SLURM_ARRAY_TASK_MIN=1, of \
                    SLURM_ARRAY_TASK_COUNT=4";
        assert_eq!(from.as_deref(), Some(said));
    }

    #[test]
    fn an_indexed_job_names_the_index_and_the_command_line_the_count() {
        assert_eq!(shard_in("auto/5", &[(COMPLETION_INDEX, "4")]), Ok((4, 5)));
        assert_eq!(shard_in("2/5", &[(COMPLETION_INDEX, "4"), (TASK_ID, "1")]), Ok((2, 5)), "K/N reads nothing");
    }

    #[test]
    fn what_names_no_shard_is_refused_with_the_variable_and_its_value() {
        let cases: [(&str, Vars, &str); 10] = [
            ("auto", &[], "SLURM_ARRAY_TASK_ID is not set; submit the job as an array"),
            ("auto", &[(COMPLETION_INDEX, "3")], "--shard auto/N with N its completions"),
            ("auto", &[(TASK_ID, "3")], "SLURM_ARRAY_TASK_ID=3 is set but SLURM_ARRAY_TASK_COUNT is not"),
            ("auto", &[(TASK_ID, "x"), (TASK_COUNT, "4")], "SLURM_ARRAY_TASK_ID=\"x\" is not a whole number"),
            ("auto", &[(TASK_ID, "+1"), (TASK_COUNT, "4")], "SLURM_ARRAY_TASK_ID=\"+1\" is not a whole number"),
            (
                "auto",
                &[(TASK_ID, "2"), (TASK_MIN, "0"), (TASK_MAX, "10"), (TASK_COUNT, "6"), (TASK_STEP, "2")],
                "SLURM_ARRAY_TASK_STEP=2: the array's ids go in steps",
            ),
            (
                "auto",
                &[(TASK_ID, "3"), (TASK_MIN, "1"), (TASK_MAX, "7"), (TASK_COUNT, "3")],
                "SLURM_ARRAY_TASK_MIN=1, SLURM_ARRAY_TASK_MAX=7 and SLURM_ARRAY_TASK_COUNT=3 are not a contiguous",
            ),
            ("auto", &[(TASK_ID, "0"), (TASK_MIN, "1"), (TASK_COUNT, "3")], "SLURM_ARRAY_TASK_ID=0 is below"),
            (
                "auto",
                &[(TASK_ID, "3"), (TASK_COUNT, "3")],
                "SLURM_ARRAY_TASK_ID=3 is not below SLURM_ARRAY_TASK_COUNT=3",
            ),
            ("auto/4", &[(COMPLETION_INDEX, "4")], "JOB_COMPLETION_INDEX=4 is not below the 4 shards"),
        ];
        for (spec, vars, says) in cases {
            let error = refused(spec, vars);
            assert!(error.contains(says), "{spec} {vars:?}: {error}");
        }
        assert!(refused("auto/4", &[]).contains("JOB_COMPLETION_INDEX is not set"));
        assert!(refused("auto/4", &[(COMPLETION_INDEX, "")]).contains("JOB_COMPLETION_INDEX=\"\" is not a whole"));
        for spec in ["auto/0", "auto/x", "auto/", "automatic", "3/3"] {
            assert!(ShardSpec::parse(spec).is_err(), "{spec}");
        }
    }
}
