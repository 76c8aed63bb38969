//! `--shard auto`: the shard from the environment of the array job the batch runs in, so the
//! same command line works under each scheduler a lab may have:
//!
//! | scheduler | index | count |
//! | --- | --- | --- |
//! | Slurm job array (`sbatch --array=A-B[:S]`) | `SLURM_ARRAY_TASK_ID`, counted from `SLURM_ARRAY_TASK_MIN` in steps of `SLURM_ARRAY_TASK_STEP` (so `--array=0-7` and `--array=1-8` both work) | `SLURM_ARRAY_TASK_COUNT` |
//! | Kubernetes Indexed Job | `JOB_COMPLETION_INDEX` (0-based) | `--shard-count` (the Job's `completions`; not in the environment) |
//! | AWS Batch array job | `AWS_BATCH_JOB_ARRAY_INDEX` (0-based) | `AWS_BATCH_JOB_ARRAY_SIZE` when set, else `--shard-count` |
//!
//! Anything missing, unparsable, out of range or contradictory (two schedulers' variables,
//! `--shard-count` against the environment's count, a Slurm task id off the array's grid) is
//! refused with a message naming the variables and their values: a shard computed wrongly would
//! silently skip or repeat sessions. [`from_env`] is a pure function of the variables, so each
//! form is tested without a scheduler.

use crate::shard::Shard;

/// What `--shard` says: a fixed `K/N`, or `auto` (from the environment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardSpec {
    Fixed(Shard),
    Auto,
}

impl std::str::FromStr for ShardSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim() == "auto" {
            return Ok(ShardSpec::Auto);
        }
        s.parse().map(ShardSpec::Fixed).map_err(|e| format!("{e}, or auto (from the array job's environment)"))
    }
}

impl ShardSpec {
    /// The shard: the fixed one (checked against `--shard-count` when given), or the
    /// environment's ([`from_env`]).
    ///
    /// # Errors
    /// What [`from_env`] refuses; a fixed `K/N` whose N is not `--shard-count`.
    pub fn resolve(self, var: &dyn Fn(&str) -> Option<String>, count_flag: Option<usize>) -> Result<Shard, String> {
        match self {
            ShardSpec::Fixed(shard) if count_flag.is_some_and(|n| n != shard.count) => {
                Err(format!("--shard {shard} but --shard-count {}", count_flag.unwrap_or_default()))
            }
            ShardSpec::Fixed(shard) => Ok(shard),
            ShardSpec::Auto => from_env(var, count_flag),
        }
    }
}

/// The schedulers' index variables, in the order they are looked for.
const INDEX_VARS: [&str; 3] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"];

/// The shard of this task, from the scheduler's variables (`var` looks one up) and the count
/// given with `--shard-count`, if any.
///
/// # Errors
/// A message naming the variables when no scheduler's index is set, more than one is, or the
/// values are missing, not numbers, out of range or disagree.
pub fn from_env(var: &dyn Fn(&str) -> Option<String>, count_flag: Option<usize>) -> Result<Shard, String> {
    let set: Vec<&str> = INDEX_VARS.iter().copied().filter(|v| var(v).is_some()).collect();
    match set.as_slice() {
        [] => Err(format!(
            "--shard auto: no array job's index in the environment (none of {} is set); \
             use --shard K/N outside a scheduler",
            INDEX_VARS.join(", ")
        )),
        ["SLURM_ARRAY_TASK_ID"] => slurm(var, count_flag),
        ["JOB_COMPLETION_INDEX"] => zero_based(var, "JOB_COMPLETION_INDEX", None, count_flag),
        ["AWS_BATCH_JOB_ARRAY_INDEX"] => {
            zero_based(var, "AWS_BATCH_JOB_ARRAY_INDEX", Some("AWS_BATCH_JOB_ARRAY_SIZE"), count_flag)
        }
        many => {
            Err(format!("--shard auto: more than one scheduler's index is set ({}): which one is it?", many.join(", ")))
        }
    }
}

/// `name`'s value as a number, or none when it is not set.
fn number(var: &dyn Fn(&str) -> Option<String>, name: &str) -> Result<Option<i64>, String> {
    var(name)
        .map(|v| v.trim().parse::<i64>().map_err(|_| format!("--shard auto: {name}={v:?} is not a whole number")))
        .transpose()
}

/// The count from the environment (`env`, if the scheduler sets one) and `--shard-count`: one of
/// them, or both equal.
fn count(env: Option<(&str, i64)>, flag: Option<usize>, scheduler: &str) -> Result<usize, String> {
    match (env, flag) {
        (None, None) => {
            Err(format!("--shard auto: the {scheduler} does not say how many tasks there are: give --shard-count N"))
        }
        (Some((name, n)), Some(f)) if n != f as i64 => {
            Err(format!("--shard auto: {name}={n} but --shard-count {f}: which is it?"))
        }
        (Some((name, n)), _) if n < 1 => Err(format!("--shard auto: {name}={n}: an array has at least one task")),
        (Some((_, n)), _) => Ok(n as usize),
        (None, Some(f)) => Ok(f),
    }
}

/// A shard from a 0-based index and a count, or what is wrong with them.
fn shard(index0: i64, count: usize, shown: &str) -> Result<Shard, String> {
    if index0 < 0 || index0 >= count as i64 {
        return Err(format!("--shard auto: {shown} is out of range for {count} tasks (0 to {})", count - 1));
    }
    Ok(Shard { index: index0 as usize + 1, count })
}

/// Kubernetes and AWS Batch: a 0-based index, the count from `count_var` or the flag.
fn zero_based(
    var: &dyn Fn(&str) -> Option<String>,
    index_var: &str,
    count_var: Option<&str>,
    count_flag: Option<usize>,
) -> Result<Shard, String> {
    let index = number(var, index_var)?.unwrap_or_default();
    let env_count = match count_var {
        Some(name) => number(var, name)?.map(|n| (name, n)),
        None => None,
    };
    let scheduler = if count_var.is_some() { "AWS Batch array job" } else { "Kubernetes Indexed Job" };
    let count = count(env_count, count_flag, scheduler)?;
    shard(index, count, &format!("{index_var}={index}"))
}

/// Slurm: the task id counted from the array's first id in its steps, the count the array's.
fn slurm(var: &dyn Fn(&str) -> Option<String>, count_flag: Option<usize>) -> Result<Shard, String> {
    let id = number(var, "SLURM_ARRAY_TASK_ID")?.unwrap_or_default();
    let min = number(var, "SLURM_ARRAY_TASK_MIN")?;
    let step = number(var, "SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
    let env_count = number(var, "SLURM_ARRAY_TASK_COUNT")?.map(|n| ("SLURM_ARRAY_TASK_COUNT", n));
    let count = count(env_count, count_flag, "Slurm array")?;
    // Without SLURM_ARRAY_TASK_MIN (Slurm always sets it; a hand-made environment may not),
    // the ids are taken as the book's recipe numbers them: 1 to N.
    let first = min.unwrap_or(1);
    if step < 1 {
        return Err(format!("--shard auto: SLURM_ARRAY_TASK_STEP={step}: a step is at least 1"));
    }
    let offset = id - first;
    if offset % step != 0 {
        return Err(format!(
            "--shard auto: SLURM_ARRAY_TASK_ID={id} is not on the array's grid (from {first} in steps of {step}); \
             arrays with listed ids (--array=1,4,9) cannot be mapped to shards: use --array=A-B[:S]"
        ));
    }
    if let Some(max) = number(var, "SLURM_ARRAY_TASK_MAX")? {
        let span = (max - first) / step + 1;
        if span != count as i64 {
            return Err(format!(
                "--shard auto: the array runs {first} to {max} in steps of {step} ({span} tasks) but has {count} tasks; \
                 arrays with listed ids (--array=1,4,9) cannot be mapped to shards: use --array=A-B[:S]"
            ));
        }
    }
    let shown = match min {
        Some(min) => format!("SLURM_ARRAY_TASK_ID={id} (array from SLURM_ARRAY_TASK_MIN={min})"),
        None => format!("SLURM_ARRAY_TASK_ID={id} (taken as 1-based: SLURM_ARRAY_TASK_MIN is not set)"),
    };
    shard(offset / step, count, &shown)
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    fn env(pairs: &[(&str, &str)], flag: Option<usize>) -> Result<Shard, String> {
        let map: HashMap<String, String> = pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        from_env(&|name| map.get(name).cloned(), flag)
    }

    fn k_of_n(index: usize, count: usize) -> Result<Shard, String> {
        Ok(Shard { index, count })
    }

    #[test]
    fn slurm_arrays_from_one_from_zero_and_in_steps() {
        let slurm = |id: &str, min: &str, max: &str, step: &str, count: &str| {
            let mut vars = vec![("SLURM_ARRAY_TASK_ID", id), ("SLURM_ARRAY_TASK_COUNT", count)];
            vars.extend([
                ("SLURM_ARRAY_TASK_MIN", min),
                ("SLURM_ARRAY_TASK_MAX", max),
                ("SLURM_ARRAY_TASK_STEP", step),
            ]);
            env(&vars, None)
        };
        // --array=1-3: ids 1, 2, 3 are shards 1/3, 2/3, 3/3.
        assert_eq!(slurm("1", "1", "3", "1", "3"), k_of_n(1, 3));
        assert_eq!(slurm("3", "1", "3", "1", "3"), k_of_n(3, 3));
        // --array=0-2: id 0 is the first shard, not an error; id 2 the last.
        assert_eq!(slurm("0", "0", "2", "1", "3"), k_of_n(1, 3));
        assert_eq!(slurm("2", "0", "2", "1", "3"), k_of_n(3, 3));
        // --array=10-30:10.
        assert_eq!(slurm("20", "10", "30", "10", "3"), k_of_n(2, 3));
        // The book's recipe's form: no MIN in a hand-made environment means 1-based.
        assert_eq!(env(&[("SLURM_ARRAY_TASK_ID", "2"), ("SLURM_ARRAY_TASK_COUNT", "4")], None), k_of_n(2, 4));
        assert_eq!(env(&[("SLURM_ARRAY_TASK_ID", "2")], Some(4)), k_of_n(2, 4));
    }

    #[test]
    fn slurm_refusals_name_the_variables() {
        let refused = |vars: &[(&str, &str)], flag, words: &[&str]| {
            let e = env(vars, flag).unwrap_err();
            assert!(words.iter().all(|w| e.contains(w)), "{e}");
        };
        let base = [("SLURM_ARRAY_TASK_MIN", "1"), ("SLURM_ARRAY_TASK_COUNT", "3")];
        refused(&[base[0], base[1], ("SLURM_ARRAY_TASK_ID", "4")], None, &["SLURM_ARRAY_TASK_ID=4", "0 to 2"]);
        refused(&[base[0], base[1], ("SLURM_ARRAY_TASK_ID", "0")], None, &["SLURM_ARRAY_TASK_ID=0"]);
        refused(&[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_COUNT", "3")], None, &["1-based"]);
        refused(&[base[0], base[1], ("SLURM_ARRAY_TASK_ID", "x")], None, &["SLURM_ARRAY_TASK_ID=\"x\""]);
        refused(
            &[base[0], base[1], ("SLURM_ARRAY_TASK_ID", "2")],
            Some(4),
            &["SLURM_ARRAY_TASK_COUNT=3", "--shard-count 4"],
        );
        refused(&[("SLURM_ARRAY_TASK_ID", "2")], None, &["--shard-count"]);
        // --array=1,4,9: three tasks whose ids are not a range.
        let listed = [base[0], base[1], ("SLURM_ARRAY_TASK_MAX", "9"), ("SLURM_ARRAY_TASK_ID", "4")];
        refused(&listed, None, &["listed ids"]);
        let stepped = [base[0], base[1], ("SLURM_ARRAY_TASK_STEP", "2"), ("SLURM_ARRAY_TASK_ID", "2")];
        refused(&stepped, None, &["grid"]);
    }

    #[test]
    fn kubernetes_indexed_jobs_count_from_zero_with_the_count_from_the_flag() {
        assert_eq!(env(&[("JOB_COMPLETION_INDEX", "0")], Some(3)), k_of_n(1, 3));
        assert_eq!(env(&[("JOB_COMPLETION_INDEX", "2")], Some(3)), k_of_n(3, 3));
        let e = env(&[("JOB_COMPLETION_INDEX", "3")], Some(3)).unwrap_err();
        assert!(e.contains("JOB_COMPLETION_INDEX=3") && e.contains("out of range"), "{e}");
        let e = env(&[("JOB_COMPLETION_INDEX", "0")], None).unwrap_err();
        assert!(e.contains("Kubernetes") && e.contains("--shard-count"), "{e}");
        assert!(env(&[("JOB_COMPLETION_INDEX", "-1")], Some(3)).is_err());
    }

    #[test]
    fn aws_batch_arrays_count_from_zero_with_the_size_from_the_environment_or_the_flag() {
        let aws = |i: &str, size: Option<&str>, flag| {
            let mut vars = vec![("AWS_BATCH_JOB_ARRAY_INDEX", i)];
            vars.extend(size.map(|s| ("AWS_BATCH_JOB_ARRAY_SIZE", s)));
            env(&vars, flag)
        };
        assert_eq!(aws("0", Some("3"), None), k_of_n(1, 3));
        assert_eq!(aws("2", Some("3"), Some(3)), k_of_n(3, 3));
        assert_eq!(aws("1", None, Some(2)), k_of_n(2, 2));
        assert!(aws("3", Some("3"), None).unwrap_err().contains("AWS_BATCH_JOB_ARRAY_INDEX=3"));
        assert!(aws("0", Some("3"), Some(4)).unwrap_err().contains("AWS_BATCH_JOB_ARRAY_SIZE=3"));
        assert!(aws("0", None, None).unwrap_err().contains("AWS Batch"));
        assert!(aws("0", Some("0"), None).unwrap_err().contains("at least one"));
    }

    #[test]
    fn shard_takes_k_of_n_or_auto_and_checks_the_count() {
        let none = |_: &str| None;
        assert_eq!("auto".parse::<ShardSpec>(), Ok(ShardSpec::Auto));
        let fixed: ShardSpec = "2/3".parse().unwrap();
        assert_eq!(fixed.resolve(&none, None), k_of_n(2, 3));
        assert_eq!(fixed.resolve(&none, Some(3)), k_of_n(2, 3));
        assert!(fixed.resolve(&none, Some(4)).unwrap_err().contains("--shard-count 4"));
        assert!("automatic".parse::<ShardSpec>().is_err());
        let slurm = |name: &str| (name == "SLURM_ARRAY_TASK_ID").then(|| "3".to_owned());
        assert_eq!(ShardSpec::Auto.resolve(&slurm, Some(3)), k_of_n(3, 3));
    }

    #[test]
    fn no_scheduler_or_two_are_refused() {
        assert!(env(&[], Some(3)).unwrap_err().contains("SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX"));
        let e = env(&[("SLURM_ARRAY_TASK_ID", "1"), ("JOB_COMPLETION_INDEX", "0")], Some(3)).unwrap_err();
        assert!(e.contains("more than one"), "{e}");
    }

    #[test]
    fn every_form_selects_what_the_matching_k_of_n_selects() {
        let names: Vec<usize> = (0..14).collect();
        for n in 1..=5usize {
            for k in 1..=n {
                let expected = Shard { index: k, count: n }.select(&names);
                let (k0, k1, n_s) = ((k - 1).to_string(), k.to_string(), n.to_string());
                let forms = [
                    env(
                        &[
                            ("SLURM_ARRAY_TASK_ID", &k1),
                            ("SLURM_ARRAY_TASK_MIN", "1"),
                            ("SLURM_ARRAY_TASK_COUNT", &n_s),
                        ],
                        None,
                    ),
                    env(
                        &[
                            ("SLURM_ARRAY_TASK_ID", &k0),
                            ("SLURM_ARRAY_TASK_MIN", "0"),
                            ("SLURM_ARRAY_TASK_COUNT", &n_s),
                        ],
                        None,
                    ),
                    env(&[("JOB_COMPLETION_INDEX", &k0)], Some(n)),
                    env(&[("AWS_BATCH_JOB_ARRAY_INDEX", &k0), ("AWS_BATCH_JOB_ARRAY_SIZE", &n_s)], None),
                ];
                for form in forms {
                    assert_eq!(form.unwrap().select(&names), expected, "{k}/{n}");
                }
            }
        }
    }
}
