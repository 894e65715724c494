//! `--emit-slurm N`: a sweep as a Slurm job array of N shards and a merge job that waits for
//! them (`afterok`), written as one bash script and computed nowhere here.
//!
//! The script has three parts, chosen by its first argument:
//!
//! - run as `bash FILE [--wait]` it submits: it checks every shard already on disk
//!   (`sweep --shard K/N --check`: its description's grid, method, records and pendula version,
//!   the file's length and CRC-32), submits an array of the shards missing or invalid only,
//!   then the merge with `--dependency=afterok:ARRAY --kill-on-invalid-dep=yes`, so that a
//!   failed or cancelled shard cancels the merge. With `--wait` it waits for the merge
//!   (`sbatch --wait`) and, when the merge did not run, names the shards that are not done;
//!   running it again computes only those.
//! - `shard` is one array task: Slurm's task IDs are 0-based, shard K = ID + 1.
//! - `merge` is the merge job: `pendula merge` of the N shards into the output (the fractal
//!   merges its own, `fractal --merge-shards`, and draws its images).
//!
//! Paths in the script are absolute (the jobs may start elsewhere than here), and every
//! value written into it is single-quoted for the shell.
//!
//! # The script, its test, and the engine's other front ends
//!
//! `--emit-slurm N` (`crates/pendula-cli/src/slurm.rs`, its flags `SlurmArgs`, for any shardable
//! command) writes a bash script that submits itself as a Slurm job array of the shards not yet
//! valid and a merge job with `afterok`; the sweep's flags written into it are parsed again and
//! must give the same fingerprint. `scripts/test-slurm` runs it on a single-node Slurm cluster
//! (`scripts/slurm-cluster.sh`: installed when missing, in a network namespace with only loopback;
//! `scripts/bench-slurm` times it); `fractal` (`crates/pendula-cli/src/commands/fractal.rs`) and
//! `bifurcation` (`crates/pendula-cli/src/commands/bifurcation.rs`) are the engine's other front
//! ends. `plot` (`crates/pendula-cli/src/commands/plot.rs`) draws any of these files — trajectory
//! panels with pendula-viz's `Figure`, grids with its `Heatmap` — and its functions draw `simulate
//! --plot`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::output::AtomicFile;
use crate::parse::{clip, parse_count};

/// The Slurm flags of a shardable command.
#[derive(Debug, Clone, Default, clap::Args, serde::Serialize, serde::Deserialize)]
pub struct SlurmArgs {
    /// Write a Slurm batch script that computes this as a job array of N shards, then merges
    /// them into --out (nothing is computed here): FILE.slurm beside --out, its shards in
    /// FILE.shards/. Submit with `bash FILE.slurm` (`--wait` to wait for the merge); running it
    /// again after a failure computes only the shards missing or invalid. N is at most the
    /// cells, and within the cluster's MaxArraySize (1001 by default).
    #[arg(long, value_name = "N", conflicts_with_all = ["shard", "checkpoint", "summary"])]
    pub emit_slurm: Option<String>,
    /// With --emit-slurm: the partition to run in [default: the cluster's].
    #[arg(long, value_name = "NAME", requires = "emit_slurm")]
    pub partition: Option<String>,
    /// With --emit-slurm: each job's time limit, as Slurm writes it (MM, HH:MM:SS,
    /// D-HH:MM:SS, ...) [default: the partition's].
    #[arg(long, value_name = "HH:MM:SS", requires = "emit_slurm")]
    pub time: Option<String>,
    /// With --emit-slurm: CPUs per shard, each shard running that many threads [default:
    /// Slurm's, one CPU per task].
    #[arg(long, value_name = "C", requires = "emit_slurm")]
    pub cpus: Option<String>,
}

/// What the script runs: the command's arguments (without --out, --shard, --threads) and
/// its output.
pub struct Plan<'a> {
    /// The subcommand (`sweep`).
    pub command: &'a str,
    /// Its arguments, reproducing the run (checked by the caller).
    pub args: Vec<String>,
    /// Whether the merge needs --allow-large.
    pub allow_large: bool,
    /// The merged output, FILE.npy.
    pub out: &'a Path,
    /// The number of cells, the most shards there may be.
    pub cells: usize,
    /// How the shards are put together: `None`, by `pendula merge`; `Some(flag)`, by the
    /// command itself given `flag SHARDS...` (fractal's `--merge-shards`, which also draws).
    pub merge_flag: Option<&'a str>,
}

/// A command's own flags for the script, as given (everything the script sets per job,
/// --out, --shard and --threads, left out), then parsed again to check they describe the same
/// run.
#[derive(Debug, Default)]
pub struct Argv(pub Vec<String>);

impl Argv {
    /// `--NAME VALUE` if given.
    pub fn value(&mut self, name: &str, value: &Option<String>) -> &mut Self {
        if let Some(v) = value {
            self.0.extend([format!("--{name}"), v.clone()]);
        }
        self
    }

    /// `--NAME VALUE` for each value.
    pub fn each(&mut self, name: &str, values: &[String]) -> &mut Self {
        for v in values {
            self.0.extend([format!("--{name}"), v.clone()]);
        }
        self
    }

    /// `--NAME` if on.
    pub fn switch(&mut self, name: &str, on: bool) -> &mut Self {
        if on {
            self.0.push(format!("--{name}"));
        }
        self
    }

    /// `pendula COMMAND ARGS... EXTRA...` as clap parses it into the command's arguments `A`:
    /// the script's command line, for the caller to compare with the run it was made from.
    pub fn parse_again<A: clap::Args>(&self, command: &str, extra: &[&str]) -> Result<A> {
        let argv = [command].into_iter().map(str::to_owned).chain(self.0.iter().cloned());
        A::augment_args(clap::Command::new("pendula"))
            .try_get_matches_from(argv.chain(extra.iter().map(|e| (*e).to_owned())))
            .and_then(|matches| A::from_arg_matches(&matches))
            .map_err(|e| {
                anyhow::anyhow!(
                    "internal error: the {command}'s arguments do not parse again for the Slurm script: {e}"
                )
            })
    }
}

/// Slurm's largest array index by default is 1000 (MaxArraySize=1001); clusters raise it.
/// N beyond this many is refused as a mistake.
const MAX_SHARDS: u64 = 1_000_000;

/// Checks the flags, writes the script beside `plan.out`, and says how to submit it.
pub fn emit(flags: &SlurmArgs, plan: &Plan) -> Result<PathBuf> {
    let text = flags.emit_slurm.as_deref().expect("called with --emit-slurm");
    let n = parse_count("--emit-slurm", text, 1, MAX_SHARDS, "shards")? as usize;
    if n > plan.cells {
        bail!("invalid --emit-slurm {n}: more shards than the {} cells", plan.cells);
    }
    if let Some(p) = &flags.partition {
        let ok = !p.is_empty() && p.bytes().all(|b| b.is_ascii_alphanumeric() || b"_-.,".contains(&b));
        if !ok {
            bail!(
                "invalid --partition `{}`: expected a partition name (letters, digits, `_`, `-`, `.`; several separated by commas)",
                clip(p)
            );
        }
    }
    if let Some(t) = &flags.time
        && !slurm_time(t)
    {
        bail!(
            "invalid --time `{}`: expected a Slurm time limit, MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS, e.g. 02:00:00",
            clip(t)
        );
    }
    let cpus = match &flags.cpus {
        Some(c) => Some(parse_count("--cpus", c, 1, 4096, "CPUs")?),
        None => None,
    };

    let cwd = std::env::current_dir().context("cannot read the working directory")?;
    let out = cwd.join(plan.out);
    let stem = out.with_extension("");
    let script_path = stem.with_extension("slurm");
    let shards = PathBuf::from(format!("{}.shards", stem.display()));
    let name = format!(
        "pendula-{}-{}",
        plan.command,
        stem.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
    );
    let exe = std::env::current_exe().context("cannot find the pendula executable")?;

    let mut s = String::new();
    let mut line = |l: &str| {
        s.push_str(l);
        s.push('\n');
    };
    line("#!/bin/bash");
    line(&format!(
        "# pendula {} as a Slurm job array of {n} shards, then their merge into {}.",
        plan.command,
        out.display()
    ));
    line(&format!(
        "# Written by `pendula {} --emit-slurm {n}` (pendula {}).",
        plan.command,
        env!("CARGO_PKG_VERSION")
    ));
    line("#");
    line(&format!(
        "#   bash {}          submit the shards not yet done, then the merge",
        script_path.display()
    ));
    line(&format!("#   bash {} --wait   the same, then wait for the merge", script_path.display()));
    line("#");
    line("# The merge runs only if every shard succeeds (afterok). After a failure, run this script");
    line("# again: it checks each shard on disk against its description (grid, method, records,");
    line("# pendula version, length and CRC-32) and submits only those missing or invalid.");
    line(&format!("#SBATCH --job-name={name}"));
    line(&format!("#SBATCH --output={}/slurm-%A_%a.out", shards.display()));
    if let Some(p) = &flags.partition {
        line(&format!("#SBATCH --partition={p}"));
    }
    if let Some(t) = &flags.time {
        line(&format!("#SBATCH --time={t}"));
    }
    if let Some(c) = cpus {
        line(&format!("#SBATCH --cpus-per-task={c}"));
    }
    line("set -euo pipefail");
    line(&format!("PENDULA=${{PENDULA:-{}}}", quote(&exe.to_string_lossy())));
    line(&format!("N={n}"));
    line(&format!("SHARDS={}", quote(&shards.to_string_lossy())));
    line(&format!("OUT={}", quote(&out.to_string_lossy())));
    line(&format!("SCRIPT={}", quote(&script_path.to_string_lossy())));
    line("# The run, as given (without --out, --shard and --threads).");
    let args: Vec<String> = plan.args.iter().map(|a| quote(a)).collect();
    line(&format!("run() {{ \"$PENDULA\" {} {} \"$@\"; }}", plan.command, args.join(" ")));
    line("# Whether shard $1 is on disk and valid (why not on stderr).");
    line("valid() {");
    line("    local why");
    line(
        "    why=$(run --shard \"$1/$N\" --out \"$SHARDS/shard-$1.npy\" --check 2>&1 >/dev/null) && return 0",
    );
    line("    echo \"  ${why#error: }\" >&2; return 1");
    line("}");
    line("");
    line("case \"${1:-submit}\" in");
    line("shard)");
    line("    # Slurm's array task IDs are 0-based; shards are 1 to N.");
    line("    k=$((SLURM_ARRAY_TASK_ID + 1))");
    line("    if valid \"$k\" 2>/dev/null; then echo \"shard $k/$N is already done\"; exit 0; fi");
    line("    run --shard \"$k/$N\" --out \"$SHARDS/shard-$k.npy\" --threads \"${SLURM_CPUS_PER_TASK:-1}\"");
    line("    ;;");
    line("merge)");
    match plan.merge_flag {
        None => line(&format!(
            "    \"$PENDULA\" merge \"$SHARDS\"/shard-{{1..{n}}}.npy --out \"$OUT\"{}",
            if plan.allow_large { " --allow-large" } else { "" }
        )),
        Some(flag) => line(&format!("    run {flag} \"$SHARDS\"/shard-{{1..{n}}}.npy --out \"$OUT\"")),
    }
    line("    ;;");
    line("submit | --wait)");
    line("    if [ -n \"${SLURM_JOB_ID:-}\" ]; then");
    line(
        "        echo \"run this script with bash, not sbatch: it submits the array and the merge itself\" >&2; exit 2",
    );
    line("    fi");
    line("    mkdir -p \"$SHARDS\"");
    line("    todo=()");
    line("    for k in $(seq 1 \"$N\"); do valid \"$k\" 2>/dev/null || todo+=(\"$((k - 1))\"); done");
    line("    dep=()");
    line("    if [ \"${#todo[@]}\" -gt 0 ]; then");
    line("        ids=$(IFS=,; echo \"${todo[*]}\")");
    line("        array=$(sbatch --parsable --array=\"$ids\" \"$SCRIPT\" shard)");
    line("        array=${array%%;*}");
    line(
        "        echo \"submitted ${#todo[@]} of $N shards as job array $array (task IDs $ids: shard = ID + 1)\"",
    );
    line("        dep=(--dependency=\"afterok:$array\" --kill-on-invalid-dep=yes)");
    line("    else");
    line("        echo \"all $N shards are done\"");
    line("    fi");
    line("    wait=(); if [ \"${1:-}\" = --wait ]; then wait=(--wait); fi");
    line(&format!(
        "    merge=$(sbatch --parsable \"${{dep[@]}}\" --cpus-per-task=1 --output=\"$SHARDS/merge-%j.out\" --job-name={name}-merge \"${{wait[@]}}\" \"$SCRIPT\" merge) && ok=1 || ok=0"
    ));
    line(
        "    if [ \"${#wait[@]}\" -eq 0 ]; then echo \"submitted the merge as job ${merge%%;*}: it writes $OUT\"; exit 0; fi",
    );
    line("    if [ \"$ok\" = 1 ] && [ -f \"$OUT\" ]; then echo \"merged into $OUT\"; exit 0; fi");
    line("    # The shards still running finish before the report: it names only those not done.");
    line(
        "    if [ -n \"${array:-}\" ]; then while [ -n \"$(squeue -h -j \"$array\" 2>/dev/null)\" ]; do sleep 1; done; fi",
    );
    line("    echo \"the merge did not run or failed; these shards are not done:\" >&2");
    line("    for k in $(seq 1 \"$N\"); do valid \"$k\" || true; done");
    line("    echo \"their logs: $SHARDS/slurm-*.out; run bash $SCRIPT again to compute only them\" >&2");
    line("    exit 1");
    line("    ;;");
    line("*)");
    line("    echo \"usage: bash $SCRIPT [--wait]\" >&2; exit 2");
    line("    ;;");
    line("esac");

    let file = AtomicFile::create(&script_path, "--emit-slurm (the script)")?;
    {
        use std::io::Write;
        let mut w = file.handle()?;
        w.write_all(s.as_bytes())?;
    }
    file.commit()?;
    Ok(script_path)
}

/// Whether `t` is a Slurm time limit: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS
/// (`--time` in sbatch(1)).
fn slurm_time(t: &str) -> bool {
    let number = |p: &str| !p.is_empty() && p.len() <= 6 && p.bytes().all(|b| b.is_ascii_digit());
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    let parts: Vec<&str> = rest.split(':').collect();
    if !parts.iter().all(|p| number(p)) || days.is_some_and(|d| !number(d)) {
        return false;
    }
    // With days or without, one to three fields follow: D-HH[:MM[:SS]] or MM[:SS], HH:MM:SS.
    (1..=3).contains(&parts.len())
}

/// `text` single-quoted for bash: nothing in it is expanded.
pub fn quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_times() {
        for ok in ["30", "30:00", "02:00:00", "1-00", "1-12:00", "2-00:00:00"] {
            assert!(slurm_time(ok), "{ok}");
        }
        for bad in ["", "1h", "1:2:3:4", "-5", "1-", "a-1", "1-1:2:3:4", "12 00"] {
            assert!(!slurm_time(bad), "{bad}");
        }
    }

    #[test]
    fn quoting_survives_the_shell() {
        let text = "a b'c\"$HOME`x`\\";
        let out = std::process::Command::new("bash")
            .arg("-c")
            .arg(format!("printf %s {}", quote(text)))
            .output()
            .expect("bash runs");
        assert_eq!(String::from_utf8_lossy(&out.stdout), text);
    }
}
