//! Checkpoint files: what `simulate`, `sweep` and `fractal` write with `--checkpoint FILE`,
//! and `pendula resume FILE` continues.
//!
//! The format, version [`VERSION`]:
//!
//! ```text
//! pendula-checkpoint 1 crc32=89abcdef
//! { ...JSON... }
//! ```
//!
//! The first line names the format, its version, and the CRC-32 of every byte after that
//! line; a file of another format or version, or whose bytes do not match the checksum, is
//! refused naming the file (exit 2). The JSON holds the command (`simulate`, `sweep`,
//! `fractal`), the working directory and the command's arguments as given (paths in them
//! are relative to that directory), a fingerprint of the validated request (a changed
//! scenario file, or another version's defaults, is refused), and the command's own state.
//! Floating-point state is stored as the IEEE 754 bit patterns of the values, in
//! hexadecimal ([`hex_words`]), so every value — NaN, infinities, −0 included — comes back
//! exactly; plain numbers in the JSON (`t`, `steps`) are for people and are not read back.
//!
//! The file is written under a temporary name and renamed into place, so it is always a
//! whole checkpoint: the previous one until the new one is complete.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use pendula::checkpoint::Words;
use serde_json::Value;

use crate::output::{AtomicFile, Guard};

/// The format's name, the first word of every checkpoint.
pub const FORMAT: &str = "pendula-checkpoint";
/// The version of the format this pendula writes and reads.
pub const VERSION: u32 = 1;

/// The largest checkpoint read (a chunked run's lists a few hundred chunks; a simulation's
/// state is a few hundred words).
const MAX_BYTES: u64 = 16 << 20;

/// What a file that is not a regular file is, for messages.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "a special file"
    }
}

/// A checkpoint's JSON, checked.
pub struct Checkpoint {
    /// Where it was read from (absolute).
    pub path: PathBuf,
    /// The JSON.
    pub body: Value,
}

impl Checkpoint {
    /// Reads and checks the checkpoint at `path`; every error names the file.
    pub fn read(path: &Path) -> Result<Self> {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        let cannot = || format!("cannot read the checkpoint {}", path.display());
        // A directory, a FIFO (which would wait for a writer) or a device is no checkpoint,
        // nor is a file far larger than any checkpoint (a trajectory given by mistake).
        let meta = std::fs::metadata(&path).with_context(cannot)?;
        if !meta.is_file() {
            bail!("{}: it is {}, not a checkpoint file", cannot(), kind(&meta));
        }
        if meta.len() > MAX_BYTES {
            bail!(
                "{} is not a checkpoint pendula can resume: it has {} bytes, and a checkpoint has at most {MAX_BYTES}",
                path.display(),
                meta.len()
            );
        }
        let bytes = std::fs::read(&path).with_context(cannot)?;
        let bad = |what: String| anyhow!("{} is not a checkpoint pendula can resume: {what}", path.display());
        let newline =
            bytes.iter().position(|&b| b == b'\n').ok_or_else(|| bad("it has no header line".into()))?;
        let header =
            std::str::from_utf8(&bytes[..newline]).map_err(|_| bad("its header is not text".into()))?;
        let mut words = header.split(' ');
        if words.next() != Some(FORMAT) {
            return Err(bad(format!("it does not start with `{FORMAT}`")));
        }
        let version = words.next().unwrap_or_default();
        if version != VERSION.to_string() {
            return Err(bad(format!(
                "it is of format version {version}, and this pendula ({}) reads version {VERSION}",
                env!("CARGO_PKG_VERSION")
            )));
        }
        let crc = words
            .next()
            .and_then(|w| w.strip_prefix("crc32="))
            .and_then(|h| u32::from_str_radix(h, 16).ok())
            .ok_or_else(|| bad("its header has no crc32=XXXXXXXX".into()))?;
        let rest = &bytes[newline + 1..];
        if crc32fast::hash(rest) != crc {
            return Err(bad(
                "its contents do not match its checksum (the file is corrupt or was edited)".into()
            ));
        }
        let body: Value = serde_json::from_slice(rest).map_err(|e| bad(format!("invalid JSON: {e}")))?;
        Ok(Checkpoint { path, body })
    }

    /// A field of the JSON, or an error naming it and the file.
    pub fn field(&self, name: &str) -> Result<&Value> {
        self.body.get(name).ok_or_else(|| anyhow!("the checkpoint {} has no `{name}`", self.path.display()))
    }

    /// A field decoded as `T`, or an error naming it and the file.
    pub fn get<T: serde::de::DeserializeOwned>(&self, name: &str) -> Result<T> {
        serde_json::from_value(self.field(name)?.clone())
            .with_context(|| format!("the checkpoint {} has an invalid `{name}`", self.path.display()))
    }

    /// A field of words ([`hex_words`]), decoded.
    pub fn words(&self, name: &str) -> Result<Words> {
        let text: String = self.get(name)?;
        words_from_hex(&text)
            .with_context(|| format!("the checkpoint {} has an invalid `{name}`", self.path.display()))
    }

    /// Refuses a checkpoint of another request than `fingerprint` (a changed scenario file,
    /// another pendula's defaults).
    pub fn check_fingerprint(&self, fingerprint: &str) -> Result<()> {
        let saved: String = self.get("fingerprint")?;
        if saved != fingerprint {
            bail!(
                "the checkpoint {} was written for another request: its arguments now validate differently (a scenario file changed, or another pendula version); start the run again",
                self.path.display()
            );
        }
        Ok(())
    }
}

/// Writes a checkpoint for `body` to `path` (which the run claimed with
/// [`crate::output::claim_regular`]), atomically; `also` runs in the same step for an
/// interrupt as the rename (it keeps the partial file the checkpoint refers to). A failed
/// write names `--checkpoint` and the path ([`crate::output::WriteError`]).
pub fn write(path: &Path, body: &Value, also: impl FnOnce(&mut Guard<'_>) -> Result<()>) -> Result<()> {
    let json = serde_json::to_vec_pretty(body)?;
    let file = AtomicFile::recreate(path, "--checkpoint")?;
    {
        use std::io::Write;
        let mut handle = file.handle()?;
        writeln!(handle, "{FORMAT} {VERSION} crc32={:08x}", crc32fast::hash(&json))?;
        handle.write_all(&json)?;
        handle.flush()?;
        handle.sync_data()?;
    }
    AtomicFile::commit_with(vec![file], also)
}

/// Removes a finished run's checkpoint (absent is fine: the run never paused).
pub fn remove(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot remove the checkpoint {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// Words as text: each word 16 hexadecimal digits, one after the other.
pub fn hex_words(words: &Words) -> String {
    let mut text = String::with_capacity(16 * words.0.len());
    for w in &words.0 {
        text.push_str(&format!("{w:016x}"));
    }
    text
}

/// The words of [`hex_words`]' text.
pub fn words_from_hex(text: &str) -> Result<Words> {
    if !text.len().is_multiple_of(16) || !text.is_ascii() {
        bail!("{} characters of hexadecimal words (16 digits each)", text.len());
    }
    (0..text.len() / 16)
        .map(|i| {
            u64::from_str_radix(&text[16 * i..16 * i + 16], 16)
                .map_err(|_| anyhow!("word {i} is not hexadecimal"))
        })
        .collect::<Result<Vec<u64>>>()
        .map(Words)
}

/// A float as 16 hexadecimal digits of its bit pattern.
pub fn hex_f64(v: f64) -> String {
    format!("{:016x}", v.to_bits())
}

/// The float of [`hex_f64`]'s text.
pub fn f64_from_hex(text: &str) -> Result<f64> {
    u64::from_str_radix(text, 16)
        .map(f64::from_bits)
        .map_err(|_| anyhow!("`{text}` is not a float's 16 hexadecimal digits"))
}

/// A digest of a description of a request (FNV-1a, 64 bits: a label that tells requests
/// apart, not a security measure).
pub fn fingerprint(text: &str) -> String {
    let hash =
        text.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    format!("{hash:016x}")
}

/// The checkpoint flags of `simulate`, `sweep` and `fractal`, checked before any file is
/// opened: the file must not be `-`, a directory, nor any of the command's outputs (by name;
/// the writer's claims also catch the same file under other names, a FIFO or a device,
/// [`crate::output::claim_regular`]). Returns the path as given, which write errors name
/// ([`absolute`] for the messages that say how to continue, from any directory).
pub fn check_path(checkpoint: &Path, outputs: &[(&str, &Path)]) -> Result<PathBuf> {
    if checkpoint.as_os_str() == "-" {
        bail!("invalid --checkpoint -: a checkpoint is a file (e.g. run.ckpt)");
    }
    if checkpoint.is_dir() {
        bail!("invalid --checkpoint {}: it is a directory", checkpoint.display());
    }
    let path = absolute(checkpoint);
    for (flag, output) in outputs {
        if absolute(output) == path {
            bail!(
                "invalid --checkpoint {}: it is also the {flag} file; give it a name of its own",
                checkpoint.display()
            );
        }
    }
    Ok(checkpoint.to_owned())
}

/// `path` from the root (as it is, if the working directory cannot be read): what the
/// messages name to continue a run with `pendula resume`, from any directory.
pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}
