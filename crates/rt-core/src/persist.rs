//! Saved structures: the file framing every structure's `save` and `load` share.
//!
//! A built structure is a few plain arrays (nodes, references, primitives) and a few numbers.
//! Saving writes them as they are, so loading is reading them back; what loading must add is
//! distrust. A file may be truncated, corrupted on disk, from another version, for another
//! structure or primitive type, or written by someone who wants a loader to read out of bounds.
//! [`Reader`] checks the framing (magic, versions, kind, the section table, every length and
//! alignment, and a checksum over the whole file), and each structure then runs its own
//! `validate` over what it read before it answers a query: a file that passes both is a
//! structure whose walks stay in bounds and end.
//!
//! # The file
//! Little-endian throughout. The header is 96 bytes:
//!
//! | bytes | what |
//! | --- | --- |
//! | 0..8 | the magic `RTACCEL` and a zero byte |
//! | 8..12 | the framing version, [`FRAMING_VERSION`] |
//! | 12..16 | the structure's own layout version |
//! | 16..48 | the structure's kind, ASCII, zero-padded (for example `rt-bvh::Bvh`) |
//! | 48..80 | the primitive type, ASCII, zero-padded (for example `Triangle`) |
//! | 80..84 | the number of sections, at most [`MAX_SECTIONS`] |
//! | 84..88 | zero |
//! | 88..96 | the checksum of every other byte ([`file_checksum`]) |
//!
//! Then one 32-byte entry per section (a tag of 8 ASCII bytes, zero-padded; the offset from the
//! file's start and the length in bytes, each a `u64`; the size of one element, a `u32`; a zero
//! `u32`), then the sections' bytes, each starting at a multiple of 16.

use bytemuck::Pod;
use std::fmt;
use std::path::{Path, PathBuf};

/// The framing version this library writes and reads.
pub const FRAMING_VERSION: u32 = 1;

/// The most sections a file may have.
pub const MAX_SECTIONS: usize = 64;

const MAGIC: [u8; 8] = *b"RTACCEL\0";
const HEADER: usize = 96;
const ENTRY: usize = 32;
const ALIGN: usize = 16;

/// Why a saved structure could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LoadError {
    /// The file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The bytes do not start with the magic: not a saved structure at all.
    NotSaved,
    /// Written by a framing or layout version this library does not read.
    Version {
        /// Which version: `"framing"` or the structure's kind.
        what: String,
        /// The version in the file.
        found: u32,
        /// The version this library reads.
        expected: u32,
    },
    /// A saved structure of another kind, or over another primitive type.
    Mismatch {
        /// `"structure"` or `"primitive"`.
        what: &'static str,
        /// What the file holds.
        found: String,
        /// What the caller asked for.
        expected: String,
    },
    /// The file ends before something it promises, or a length or offset is inconsistent.
    Malformed(String),
    /// The checksum does not match: the bytes changed after they were written.
    Checksum,
    /// The framing is sound, but the structure it holds breaks an invariant.
    Invalid(crate::ValidationError),
    /// [`LoadError`] from a file, naming it.
    InFile {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        error: Box<LoadError>,
    },
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Io { path, message } => {
                write!(f, "{}: cannot read: {message}", path.display())
            }
            LoadError::NotSaved => write!(f, "not a saved rt-accel structure (no RTACCEL magic)"),
            LoadError::Version {
                what,
                found,
                expected,
            } => write!(
                f,
                "{what} version {found} is not supported (this library reads version {expected})"
            ),
            LoadError::Mismatch {
                what,
                found,
                expected,
            } => write!(f, "the file holds {what} `{found}`, not `{expected}`"),
            LoadError::Malformed(m) => write!(f, "malformed file: {m}"),
            LoadError::Checksum => write!(f, "checksum mismatch: the file was changed or damaged"),
            LoadError::Invalid(e) => write!(f, "the saved structure is invalid: {e}"),
            LoadError::InFile { path, error } => write!(f, "{}: {error}", path.display()),
        }
    }
}

impl std::error::Error for LoadError {}

/// A primitive type a structure can be saved over: plain old data, with a name the file
/// records so that a file over other primitives is refused.
pub trait SavedPrimitive: crate::Primitive + Pod {
    /// The name recorded in the file (at most 32 ASCII bytes).
    const NAME: &'static str;
}

impl SavedPrimitive for crate::Triangle {
    const NAME: &'static str = "Triangle";
}

impl SavedPrimitive for crate::MtTriangle {
    const NAME: &'static str = "MtTriangle";
}

impl SavedPrimitive for crate::Sphere {
    const NAME: &'static str = "Sphere";
}

/// A checksum of `bytes`: four lanes of multiply–rotate over 8-byte words, folded. It catches
/// damage, not an adversary (validation does that), and runs at memory speed.
pub fn checksum(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut lanes = [1u64, 2, 3, 4];
    let mut chunks = bytes.chunks_exact(32);
    for chunk in &mut chunks {
        for (lane, word) in lanes.iter_mut().zip(chunk.chunks_exact(8)) {
            let w = u64::from_le_bytes(word.try_into().unwrap_or([0; 8]));
            *lane = (*lane ^ w).wrapping_mul(K).rotate_left(29);
        }
    }
    let mut tail = [0u8; 32];
    let rest = chunks.remainder();
    tail[..rest.len()].copy_from_slice(rest);
    for (lane, word) in lanes.iter_mut().zip(tail.chunks_exact(8)) {
        let w = u64::from_le_bytes(word.try_into().unwrap_or([0; 8]));
        *lane = (*lane ^ w).wrapping_mul(K).rotate_left(29);
    }
    lanes.iter().fold(bytes.len() as u64, |h, &l| {
        (h ^ l).wrapping_mul(K).rotate_left(31)
    })
}

/// The checksum a file records: [`checksum`] of the header before the checksum field, and of
/// everything after the header, combined. Every byte but the field itself counts.
pub fn file_checksum(bytes: &[u8]) -> u64 {
    let (head, rest) = (
        &bytes[..88.min(bytes.len())],
        bytes.get(HEADER..).unwrap_or(&[]),
    );
    checksum(head).rotate_left(17) ^ checksum(rest)
}

/// A name padded into a fixed field: at most 32 ASCII bytes.
fn field(name: &str) -> [u8; 32] {
    let mut out = [0u8; 32];
    for (o, b) in out.iter_mut().zip(name.bytes()) {
        *o = b;
    }
    out
}

fn name_of(field: &[u8]) -> String {
    let end = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    String::from_utf8_lossy(&field[..end]).into_owned()
}

/// Writes a saved structure: its sections in order, then [`Writer::finish`].
pub struct Writer {
    kind: &'static str,
    layout: u32,
    prim: &'static str,
    sections: Vec<([u8; 8], Vec<u8>, u32)>,
}

impl Writer {
    /// A file for structure `kind` (layout version `layout`) over primitives `P`.
    pub fn new<P: SavedPrimitive>(kind: &'static str, layout: u32) -> Self {
        Self {
            kind,
            layout,
            prim: P::NAME,
            sections: Vec::new(),
        }
    }

    /// Adds the section `tag` (at most 8 ASCII bytes) holding `data`.
    pub fn section<T: Pod>(&mut self, tag: &str, data: &[T]) {
        let mut t = [0u8; 8];
        for (o, b) in t.iter_mut().zip(tag.bytes()) {
            *o = b;
        }
        self.sections.push((
            t,
            bytemuck::cast_slice(data).to_vec(),
            std::mem::size_of::<T>() as u32,
        ));
    }

    /// The file's bytes.
    pub fn finish(self) -> Vec<u8> {
        let table = HEADER + ENTRY * self.sections.len();
        let mut offset = table.next_multiple_of(ALIGN);
        let mut entries = Vec::with_capacity(self.sections.len());
        for (_, bytes, _) in &self.sections {
            entries.push((offset, bytes.len()));
            offset = (offset + bytes.len()).next_multiple_of(ALIGN);
        }
        let mut out = vec![0u8; offset];
        out[0..8].copy_from_slice(&MAGIC);
        out[8..12].copy_from_slice(&FRAMING_VERSION.to_le_bytes());
        out[12..16].copy_from_slice(&self.layout.to_le_bytes());
        out[16..48].copy_from_slice(&field(self.kind));
        out[48..80].copy_from_slice(&field(self.prim));
        out[80..84].copy_from_slice(&(self.sections.len() as u32).to_le_bytes());
        for (i, ((tag, bytes, size), (at, len))) in self.sections.iter().zip(entries).enumerate() {
            let e = HEADER + ENTRY * i;
            out[e..e + 8].copy_from_slice(tag);
            out[e + 8..e + 16].copy_from_slice(&(at as u64).to_le_bytes());
            out[e + 16..e + 24].copy_from_slice(&(len as u64).to_le_bytes());
            out[e + 24..e + 28].copy_from_slice(&size.to_le_bytes());
            out[at..at + len].copy_from_slice(bytes);
        }
        let sum = file_checksum(&out);
        out[88..96].copy_from_slice(&sum.to_le_bytes());
        out
    }
}

impl fmt::Debug for Writer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Writer")
            .field("kind", &self.kind)
            .field("layout", &self.layout)
            .field("prim", &self.prim)
            .field("sections", &self.sections.len())
            .finish()
    }
}

/// Reads a saved structure's sections, every length and offset checked.
pub struct Reader<'a> {
    bytes: &'a [u8],
    entries: Vec<([u8; 8], usize, usize, usize)>,
}

impl<'a> Reader<'a> {
    /// Checks the framing of `bytes` as a file of structure `kind` (layout version `layout`)
    /// over primitives `P`: magic, versions, kind, primitive type, the section table (every
    /// section inside the file, aligned, a whole number of elements) and the checksum.
    ///
    /// # Errors
    /// The first thing found wrong.
    pub fn new<P: SavedPrimitive>(
        bytes: &'a [u8],
        kind: &str,
        layout: u32,
    ) -> Result<Self, LoadError> {
        let malformed = |m: String| Err(LoadError::Malformed(m));
        if bytes.len() < 8 || bytes[0..8] != MAGIC {
            return Err(LoadError::NotSaved);
        }
        if bytes.len() < HEADER {
            return malformed(format!(
                "{} bytes, shorter than the {HEADER}-byte header",
                bytes.len()
            ));
        }
        let u32_at = |at: usize| {
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        let u64_at = |at: usize| {
            let mut w = [0u8; 8];
            w.copy_from_slice(&bytes[at..at + 8]);
            u64::from_le_bytes(w)
        };
        let framing = u32_at(8);
        if framing != FRAMING_VERSION {
            return Err(LoadError::Version {
                what: "framing".into(),
                found: framing,
                expected: FRAMING_VERSION,
            });
        }
        let found_kind = name_of(&bytes[16..48]);
        if found_kind != kind {
            return Err(LoadError::Mismatch {
                what: "structure",
                found: found_kind,
                expected: kind.into(),
            });
        }
        let found_layout = u32_at(12);
        if found_layout != layout {
            return Err(LoadError::Version {
                what: kind.into(),
                found: found_layout,
                expected: layout,
            });
        }
        let found_prim = name_of(&bytes[48..80]);
        if found_prim != P::NAME {
            return Err(LoadError::Mismatch {
                what: "primitive",
                found: found_prim,
                expected: P::NAME.into(),
            });
        }
        let count = u32_at(80) as usize;
        if count > MAX_SECTIONS {
            return malformed(format!("{count} sections, more than {MAX_SECTIONS}"));
        }
        if bytes.len() < HEADER + ENTRY * count {
            return malformed(format!(
                "{} bytes, too short for the table of {count} sections",
                bytes.len()
            ));
        }
        if file_checksum(bytes) != u64_at(88) {
            return Err(LoadError::Checksum);
        }
        let mut entries = Vec::with_capacity(count);
        for i in 0..count {
            let e = HEADER + ENTRY * i;
            let mut tag = [0u8; 8];
            tag.copy_from_slice(&bytes[e..e + 8]);
            let (at, len, size) = (u64_at(e + 8), u64_at(e + 16), u32_at(e + 24) as usize);
            let end = at.checked_add(len);
            if end.is_none_or(|end| end > bytes.len() as u64) || at % ALIGN as u64 != 0 {
                return malformed(format!(
                    "section `{}` at {at}, {len} bytes, is not an aligned part of the {}-byte file",
                    name_of(&tag),
                    bytes.len()
                ));
            }
            if size == 0 || len % size as u64 != 0 {
                return malformed(format!(
                    "section `{}` of {len} bytes is not a whole number of {size}-byte elements",
                    name_of(&tag)
                ));
            }
            entries.push((tag, at as usize, len as usize, size));
        }
        Ok(Self { bytes, entries })
    }

    /// The elements of section `tag`, copied out (so the file's bytes need no alignment).
    ///
    /// # Errors
    /// [`LoadError::Malformed`] when there is no such section or its elements are not `T`'s
    /// size.
    pub fn section<T: Pod>(&self, tag: &str) -> Result<Vec<T>, LoadError> {
        let key = {
            let mut t = [0u8; 8];
            for (o, b) in t.iter_mut().zip(tag.bytes()) {
                *o = b;
            }
            t
        };
        let Some(&(_, at, len, size)) = self.entries.iter().find(|e| e.0 == key) else {
            return Err(LoadError::Malformed(format!("no section `{tag}`")));
        };
        if size != std::mem::size_of::<T>() {
            return Err(LoadError::Malformed(format!(
                "section `{tag}` has {size}-byte elements, not {}",
                std::mem::size_of::<T>()
            )));
        }
        let mut out = vec![T::zeroed(); len / size];
        bytemuck::cast_slice_mut::<T, u8>(&mut out).copy_from_slice(&self.bytes[at..at + len]);
        Ok(out)
    }

    /// The one element of section `tag`.
    ///
    /// # Errors
    /// As [`section`](Reader::section), and when the section does not hold exactly one element.
    pub fn value<T: Pod>(&self, tag: &str) -> Result<T, LoadError> {
        match self.section::<T>(tag)?[..] {
            [v] => Ok(v),
            ref other => Err(LoadError::Malformed(format!(
                "section `{tag}` holds {} values, not 1",
                other.len()
            ))),
        }
    }
}

impl fmt::Debug for Reader<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sections: Vec<String> = self
            .entries
            .iter()
            .map(|(tag, _, len, _)| format!("{} ({len} bytes)", name_of(tag)))
            .collect();
        f.debug_struct("Reader")
            .field("bytes", &self.bytes.len())
            .field("sections", &sections)
            .finish()
    }
}

/// Reads the file at `path`, naming it in any error.
///
/// # Errors
/// [`LoadError::Io`] when the file cannot be read.
pub fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| LoadError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Sphere, Triangle};

    fn sample() -> Vec<u8> {
        let mut w = Writer::new::<Triangle>("test::Thing", 3);
        w.section("nodes", &[1u32, 2, 3, 4, 5]);
        w.section("bounds", &[1.5f32; 6]);
        w.section("empty", &[0u64; 0]);
        w.finish()
    }

    #[test]
    fn sections_read_back_as_written() {
        let bytes = sample();
        assert_eq!(bytes.len() % ALIGN, 0);
        let r = Reader::new::<Triangle>(&bytes, "test::Thing", 3).unwrap();
        assert_eq!(r.section::<u32>("nodes").unwrap(), [1, 2, 3, 4, 5]);
        assert_eq!(r.section::<f32>("bounds").unwrap(), [1.5; 6]);
        assert!(r.section::<u64>("empty").unwrap().is_empty());
        assert!(matches!(
            r.section::<u32>("none"),
            Err(LoadError::Malformed(_))
        ));
        assert!(matches!(
            r.section::<u64>("nodes"),
            Err(LoadError::Malformed(_))
        ));
        assert!(matches!(
            r.value::<u32>("nodes"),
            Err(LoadError::Malformed(_))
        ));
    }

    #[test]
    fn the_wrong_kind_version_or_primitive_is_refused_by_name() {
        let bytes = sample();
        let e = Reader::new::<Triangle>(&bytes, "test::Other", 3)
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "the file holds structure `test::Thing`, not `test::Other`"
        );
        let e = Reader::new::<Triangle>(&bytes, "test::Thing", 4)
            .err()
            .unwrap();
        assert!(
            matches!(
                e,
                LoadError::Version {
                    found: 3,
                    expected: 4,
                    ..
                }
            ),
            "{e}"
        );
        let e = Reader::new::<Sphere>(&bytes, "test::Thing", 3)
            .err()
            .unwrap();
        assert!(
            e.to_string().contains("primitive `Triangle`, not `Sphere`"),
            "{e}"
        );
        assert_eq!(
            Reader::new::<Triangle>(b"hello", "test::Thing", 3).err(),
            Some(LoadError::NotSaved)
        );
    }

    /// Every truncation and every single flipped bit is refused, none panics.
    #[test]
    fn truncated_or_damaged_files_are_refused() {
        let bytes = sample();
        for len in 0..bytes.len() {
            assert!(
                Reader::new::<Triangle>(&bytes[..len], "test::Thing", 3).is_err(),
                "{len}"
            );
        }
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                assert!(
                    Reader::new::<Triangle>(&b, "test::Thing", 3).is_err(),
                    "byte {i} bit {bit} went unnoticed"
                );
            }
        }
    }

    /// A hostile table (sections past the end, overflowing offsets, misaligned, ragged) with a
    /// correct checksum is refused as malformed.
    #[test]
    fn a_hostile_table_with_a_good_checksum_is_malformed() {
        let bytes = sample();
        let first = HEADER;
        for (field_at, value) in [
            (first + 8, u64::MAX - 7),
            (first + 8, 1 << 40),
            (first + 8, 8),
            (first + 16, u64::MAX),
            (first + 16, 7),
        ] {
            let mut b = bytes.clone();
            b[field_at..field_at + 8].copy_from_slice(&value.to_le_bytes());
            let sum = file_checksum(&b);
            b[88..96].copy_from_slice(&sum.to_le_bytes());
            let e = Reader::new::<Triangle>(&b, "test::Thing", 3).err();
            assert!(
                matches!(e, Some(LoadError::Malformed(_))),
                "{field_at} = {value}: {e:?}"
            );
        }
        let mut b = bytes.clone();
        b[80..84].copy_from_slice(&1000u32.to_le_bytes());
        let sum = file_checksum(&b);
        b[88..96].copy_from_slice(&sum.to_le_bytes());
        assert!(matches!(
            Reader::new::<Triangle>(&b, "test::Thing", 3),
            Err(LoadError::Malformed(_))
        ));
    }

    /// Random damage, with the checksum recomputed half the time so the table is reached: an
    /// error or a reader whose sections read back, never a panic.
    #[test]
    fn random_damage_never_panics() {
        let bytes = sample();
        let mut rng = crate::Rng::new(5);
        for round in 0..20_000 {
            let mut b = bytes.clone();
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(b.len() as u32) as usize;
                b[i] = rng.next_u32() as u8;
            }
            if round % 2 == 0 {
                let sum = file_checksum(&b);
                b[88..96].copy_from_slice(&sum.to_le_bytes());
            }
            let cut = if round % 7 == 0 {
                rng.below(b.len() as u32) as usize
            } else {
                b.len()
            };
            if let Ok(r) = Reader::new::<Triangle>(&b[..cut], "test::Thing", 3) {
                for tag in ["nodes", "bounds", "empty"] {
                    let _ = r.section::<u32>(tag);
                    let _ = r.section::<f32>(tag);
                    let _ = r.value::<u64>(tag);
                }
            }
        }
    }
}
