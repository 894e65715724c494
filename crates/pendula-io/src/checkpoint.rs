//! Checkpoint files: what `simulate`, `sweep` and `fractal` write with `--checkpoint FILE`,
//! and `pendula resume FILE` continues: their format ([`encode`], [`Checkpoint::read`]) and
//! the encodings of exact state ([`hex_words`], [`hex_f64`], [`fingerprint`]).
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
//! The file is written (by the front end, which owns the file) under a temporary name and
//! renamed into place, so it is always a whole checkpoint: the previous one until the new
//! one is complete.

use std::path::{Path, PathBuf};

use pendula::checkpoint::Words;
use serde_json::Value;

use crate::{Result, caused, invalid};

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
#[derive(Debug, Clone)]
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
        let meta = std::fs::metadata(&path).map_err(|e| caused(cannot(), &e))?;
        if !meta.is_file() {
            return Err(invalid!("{}: it is {}, not a checkpoint file", cannot(), kind(&meta)));
        }
        if meta.len() > MAX_BYTES {
            return Err(invalid!(
                "{} is not a checkpoint pendula can resume: it has {} bytes, and a checkpoint has at most {MAX_BYTES}",
                path.display(),
                meta.len()
            ));
        }
        let bytes = std::fs::read(&path).map_err(|e| caused(cannot(), &e))?;
        let bad =
            |what: String| invalid!("{} is not a checkpoint pendula can resume: {what}", path.display());
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
        self.body.get(name).ok_or_else(|| invalid!("the checkpoint {} has no `{name}`", self.path.display()))
    }

    /// A field decoded as `T`, or an error naming it and the file.
    pub fn get<T: serde::de::DeserializeOwned>(&self, name: &str) -> Result<T> {
        serde_json::from_value(self.field(name)?.clone()).map_err(|e| {
            caused(format!("the checkpoint {} has an invalid `{name}`", self.path.display()), &e)
        })
    }

    /// A field of words ([`hex_words`]), decoded.
    pub fn words(&self, name: &str) -> Result<Words> {
        let text: String = self.get(name)?;
        words_from_hex(&text).map_err(|e| {
            caused(format!("the checkpoint {} has an invalid `{name}`", self.path.display()), &e)
        })
    }

    /// Refuses a checkpoint of another request than `fingerprint` (a changed scenario file,
    /// another pendula's defaults).
    pub fn check_fingerprint(&self, fingerprint: &str) -> Result<()> {
        let saved: String = self.get("fingerprint")?;
        if saved != fingerprint {
            return Err(invalid!(
                "the checkpoint {} was written for another request: its arguments now validate differently (a scenario file changed, or another pendula version); start the run again",
                self.path.display()
            ));
        }
        Ok(())
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
        return Err(invalid!("{} characters of hexadecimal words (16 digits each)", text.len()));
    }
    (0..text.len() / 16)
        .map(|i| {
            u64::from_str_radix(&text[16 * i..16 * i + 16], 16)
                .map_err(|_| invalid!("word {i} is not hexadecimal"))
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
        .map_err(|_| invalid!("`{text}` is not a float's 16 hexadecimal digits"))
}

/// A digest of a description of a request (FNV-1a, 64 bits: a label that tells requests
/// apart, not a security measure).
pub fn fingerprint(text: &str) -> String {
    let hash =
        text.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    format!("{hash:016x}")
}

/// The bytes of a checkpoint of `body`: the header line (format, version, CRC-32 of what
/// follows it), then the JSON, pretty-printed.
pub fn encode(body: &Value) -> Vec<u8> {
    let json = serde_json::to_vec_pretty(body).expect("JSON values serialise");
    let mut bytes = format!("{FORMAT} {VERSION} crc32={:08x}\n", crc32fast::hash(&json)).into_bytes();
    bytes.extend_from_slice(&json);
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_read_back_and_their_words_exactly() {
        let dir = std::env::temp_dir().join(format!("pendula-io-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary directory");
        let path = dir.join("run.ckpt");
        let words = Words(vec![f64::NAN.to_bits(), (-0.0f64).to_bits(), 1.5f64.to_bits()]);
        let body = serde_json::json!({"command": "simulate", "state": hex_words(&words), "t": hex_f64(-0.0),
                                      "fingerprint": fingerprint("a request")});
        std::fs::write(&path, encode(&body)).expect("written");
        let c = Checkpoint::read(&path).expect("a checkpoint");
        assert_eq!(c.body, body);
        assert_eq!(c.words("state").expect("words").0, words.0);
        assert_eq!(
            f64_from_hex(&c.get::<String>("t").expect("t")).expect("a float").to_bits(),
            (-0.0f64).to_bits()
        );
        c.check_fingerprint(&fingerprint("a request")).expect("the same request");
        assert!(
            c.check_fingerprint(&fingerprint("another")).unwrap_err().to_string().contains("another request")
        );
        assert!(c.field("absent").unwrap_err().to_string().ends_with("has no `absent`"));
        // One byte changed after the header: the checksum refuses it.
        let mut bytes = encode(&body);
        *bytes.last_mut().expect("bytes") ^= 1;
        std::fs::write(&path, bytes).expect("written");
        let e = Checkpoint::read(&path).unwrap_err().to_string();
        assert!(
            e.ends_with("its contents do not match its checksum (the file is corrupt or was edited)"),
            "{e}"
        );
        let e = Checkpoint::read(&dir).unwrap_err().to_string();
        assert!(e.ends_with("it is a directory, not a checkpoint file"), "{e}");
        std::fs::remove_dir_all(&dir).expect("removed");
        assert!(words_from_hex("abc").is_err() && f64_from_hex("zz").is_err());
    }
}
