//! Saved structures: the [`Persist`] trait every structure crate implements, and the file
//! framing every structure's `save` and `load` share.
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

#![warn(missing_docs)]

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
    Invalid(rt_core::ValidationError),
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

impl From<rt_core::ValidationError> for LoadError {
    fn from(e: rt_core::ValidationError) -> Self {
        LoadError::Invalid(e)
    }
}

/// A primitive type a structure can be saved over: plain old data, with a name the file
/// records so that a file over other primitives is refused.
pub trait SavedPrimitive: rt_core::Primitive + Pod {
    /// The name recorded in the file (at most 32 ASCII bytes).
    const NAME: &'static str;
}

impl SavedPrimitive for rt_core::Triangle {
    const NAME: &'static str = "Triangle";
}

impl SavedPrimitive for rt_core::MtTriangle {
    const NAME: &'static str = "MtTriangle";
}

impl SavedPrimitive for rt_core::Sphere {
    const NAME: &'static str = "Sphere";
}

/// A checksum of `bytes`: four lanes of multiply–rotate over 8-byte words, folded. It catches
/// damage, not an adversary (validation does that), and runs at memory speed.
pub fn checksum(bytes: &[u8]) -> u64 {
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
    lanes.iter().fold(bytes.len() as u64, |h, &l| fold(h, l))
}

const K: u64 = 0x9E37_79B9_7F4A_7C15;

fn fold(h: u64, x: u64) -> u64 {
    (h ^ x).wrapping_mul(K).rotate_left(31)
}

/// A section's checksum is taken over blocks of this many bytes, so that a large section is
/// read and checked on several threads.
const BLOCK: usize = 1 << 20;

/// A section's checksum: [`checksum`] of each block of 1 MiB, folded in order.
pub fn section_checksum(bytes: &[u8]) -> u64 {
    fold_blocks(bytes.len(), bytes.chunks(BLOCK).map(checksum))
}

fn fold_blocks(len: usize, blocks: impl IntoIterator<Item = u64>) -> u64 {
    blocks.into_iter().fold(len as u64, fold)
}

/// The checksum a file records: [`checksum`] of the header before the checksum field and of
/// the section table, and [`section_checksum`] of each section, folded in order. Every other
/// byte of a file is padding that must be zero, so every byte but the field itself counts.
/// (For bytes whose table does not parse, the [`checksum`] of all of them: such a file is
/// refused as malformed before its checksum is looked at.)
pub fn file_checksum(bytes: &[u8]) -> u64 {
    match layout(bytes, bytes.len() as u64) {
        Ok(entries) => combine(
            &bytes[..HEADER],
            &bytes[HEADER..HEADER + ENTRY * entries.len()],
            entries
                .iter()
                .map(|e| section_checksum(&bytes[e.at..e.at + e.len])),
        ),
        Err(_) => checksum(bytes),
    }
}

fn combine(header: &[u8], table: &[u8], sections: impl IntoIterator<Item = u64>) -> u64 {
    let start = fold(checksum(&header[..88]).rotate_left(17), checksum(table));
    sections.into_iter().fold(start, fold)
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

fn tag_of(tag: &str) -> [u8; 8] {
    let mut t = [0u8; 8];
    for (o, b) in t.iter_mut().zip(tag.bytes()) {
        *o = b;
    }
    t
}

/// Writes a saved structure: its sections in order, then [`Writer::finish`] for the bytes or
/// [`Writer::write_to`] for a file. Sections borrow their data where they can, so writing a
/// large structure to a file copies nothing.
pub struct Writer<'a> {
    kind: &'static str,
    layout: u32,
    prim: &'static str,
    sections: Vec<([u8; 8], std::borrow::Cow<'a, [u8]>, u32)>,
}

impl<'a> Writer<'a> {
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
    pub fn section<T: Pod>(&mut self, tag: &str, data: &'a [T]) {
        self.sections.push((
            tag_of(tag),
            std::borrow::Cow::Borrowed(bytemuck::cast_slice(data)),
            std::mem::size_of::<T>() as u32,
        ));
    }

    /// Adds the section `tag` holding `data`, made for the file.
    pub fn section_owned<T: Pod>(&mut self, tag: &str, data: Vec<T>) {
        self.sections.push((
            tag_of(tag),
            std::borrow::Cow::Owned(bytemuck::cast_slice(&data).to_vec()),
            std::mem::size_of::<T>() as u32,
        ));
    }

    /// The header and the table, checksum included, and each section's offset, then the
    /// file's length.
    fn head(&self) -> (Vec<u8>, Vec<usize>) {
        let table = HEADER + ENTRY * self.sections.len();
        let mut head = vec![0u8; table];
        head[0..8].copy_from_slice(&MAGIC);
        head[8..12].copy_from_slice(&FRAMING_VERSION.to_le_bytes());
        head[12..16].copy_from_slice(&self.layout.to_le_bytes());
        head[16..48].copy_from_slice(&field(self.kind));
        head[48..80].copy_from_slice(&field(self.prim));
        head[80..84].copy_from_slice(&(self.sections.len() as u32).to_le_bytes());
        let mut at = table.next_multiple_of(ALIGN);
        let mut offsets = Vec::with_capacity(self.sections.len() + 1);
        for (i, (tag, bytes, size)) in self.sections.iter().enumerate() {
            let e = HEADER + ENTRY * i;
            head[e..e + 8].copy_from_slice(tag);
            head[e + 8..e + 16].copy_from_slice(&(at as u64).to_le_bytes());
            head[e + 16..e + 24].copy_from_slice(&(bytes.len() as u64).to_le_bytes());
            head[e + 24..e + 28].copy_from_slice(&size.to_le_bytes());
            offsets.push(at);
            at = (at + bytes.len()).next_multiple_of(ALIGN);
        }
        offsets.push(at);
        let sum = combine(
            &head[..HEADER],
            &head[HEADER..],
            self.sections.iter().map(|(_, b, _)| section_checksum(b)),
        );
        head[88..96].copy_from_slice(&sum.to_le_bytes());
        (head, offsets)
    }

    /// The file's bytes.
    pub fn finish(self) -> Vec<u8> {
        let (head, offsets) = self.head();
        let mut out = vec![0u8; offsets[offsets.len() - 1]];
        out[..head.len()].copy_from_slice(&head);
        for ((_, bytes, _), at) in self.sections.iter().zip(&offsets) {
            out[*at..*at + bytes.len()].copy_from_slice(bytes);
        }
        out
    }

    /// Writes the file's bytes to `out`, the sections straight from where they are.
    ///
    /// # Errors
    /// What `out` reports.
    pub fn write_to(self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        let (head, offsets) = self.head();
        out.write_all(&head)?;
        let mut written = head.len();
        for ((_, bytes, _), &at) in self.sections.iter().zip(&offsets) {
            out.write_all(&[0u8; ALIGN][..at - written])?;
            out.write_all(bytes)?;
            written = at + bytes.len();
        }
        out.write_all(&[0u8; ALIGN][..offsets[offsets.len() - 1] - written])
    }
}

impl fmt::Debug for Writer<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Writer")
            .field("kind", &self.kind)
            .field("layout", &self.layout)
            .field("prim", &self.prim)
            .field("sections", &self.sections.len())
            .finish()
    }
}

/// One section of a file: its tag, where it starts, its length and its element size.
#[derive(Clone, Copy, Debug)]
struct Entry {
    tag: [u8; 8],
    at: usize,
    len: usize,
    size: usize,
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&bytes[at..at + 8]);
    u64::from_le_bytes(w)
}

/// The section table of a file of `file_len` bytes that starts with `head` (at least its
/// header and table): every section where the writer puts it (the first after the table, each
/// next one after the one before, each at a multiple of 16), a whole number of elements, and
/// the file ending with the last.
fn layout(head: &[u8], file_len: u64) -> Result<Vec<Entry>, LoadError> {
    let malformed = |m: String| Err(LoadError::Malformed(m));
    if head.len() < HEADER {
        return malformed(format!(
            "{file_len} bytes, shorter than the {HEADER}-byte header"
        ));
    }
    let count = u32_at(head, 80) as usize;
    if count > MAX_SECTIONS {
        return malformed(format!("{count} sections, more than {MAX_SECTIONS}"));
    }
    if head.len() < HEADER + ENTRY * count {
        return malformed(format!(
            "{file_len} bytes, too short for the table of {count} sections"
        ));
    }
    let mut next = (HEADER + ENTRY * count).next_multiple_of(ALIGN) as u64;
    let mut entries = Vec::with_capacity(count);
    for i in 0..count {
        let e = HEADER + ENTRY * i;
        let mut tag = [0u8; 8];
        tag.copy_from_slice(&head[e..e + 8]);
        let (at, len, size) = (
            u64_at(head, e + 8),
            u64_at(head, e + 16),
            u32_at(head, e + 24),
        );
        let end = at.checked_add(len);
        if at != next || end.is_none_or(|end| end > file_len) {
            return malformed(format!(
                "section `{}` at {at}, {len} bytes, is not where it belongs in the \
                 {file_len}-byte file",
                name_of(&tag)
            ));
        }
        if size == 0 || len % u64::from(size) != 0 {
            return malformed(format!(
                "section `{}` of {len} bytes is not a whole number of {size}-byte elements",
                name_of(&tag)
            ));
        }
        next = (at + len).next_multiple_of(ALIGN as u64);
        entries.push(Entry {
            tag,
            at: at as usize,
            len: len as usize,
            size: size as usize,
        });
    }
    if next != file_len {
        return malformed(format!(
            "the sections end at {next}, but the file has {file_len} bytes"
        ));
    }
    Ok(entries)
}

/// Checks the header of a file: magic, versions, kind and primitive type.
fn check_header<P: SavedPrimitive>(head: &[u8], kind: &str, layout: u32) -> Result<(), LoadError> {
    if head.len() < 8 || head[0..8] != MAGIC {
        return Err(LoadError::NotSaved);
    }
    if head.len() < HEADER {
        return Err(LoadError::Malformed(format!(
            "{} bytes, shorter than the {HEADER}-byte header",
            head.len()
        )));
    }
    let framing = u32_at(head, 8);
    if framing != FRAMING_VERSION {
        return Err(LoadError::Version {
            what: "framing".into(),
            found: framing,
            expected: FRAMING_VERSION,
        });
    }
    let found_kind = name_of(&head[16..48]);
    if found_kind != kind {
        return Err(LoadError::Mismatch {
            what: "structure",
            found: found_kind,
            expected: kind.into(),
        });
    }
    let found_layout = u32_at(head, 12);
    if found_layout != layout {
        return Err(LoadError::Version {
            what: kind.into(),
            found: found_layout,
            expected: layout,
        });
    }
    let found_prim = name_of(&head[48..80]);
    if found_prim != P::NAME {
        return Err(LoadError::Mismatch {
            what: "primitive",
            found: found_prim,
            expected: P::NAME.into(),
        });
    }
    Ok(())
}

/// Where a [`Reader`] reads from.
enum Source<'a> {
    Bytes(&'a [u8]),
    File(std::fs::File),
}

/// Reads a saved structure's sections, every length and offset checked.
///
/// From bytes ([`Reader::new`]), the checksum is checked at once. From a file
/// ([`Reader::open`]), each section is read straight into the array it becomes, block by block
/// on the builders' threads, its checksum taken as it is read; [`Reader::finish`] reads what
/// was not asked for and checks the file's checksum. So a loader reads its sections, calls
/// `finish`, and only then validates what it read.
pub struct Reader<'a> {
    source: Source<'a>,
    entries: Vec<Entry>,
    /// The header and the table, for the checksum.
    head: Vec<u8>,
    /// Each section's checksum, once read.
    sums: std::sync::Mutex<Vec<Option<u64>>>,
}

impl<'a> Reader<'a> {
    /// Checks the framing of `bytes` as a file of structure `kind` (layout version `layout`)
    /// over primitives `P`: magic, versions, kind, primitive type, the section table (every
    /// section where the writer puts it, a whole number of elements), the zero padding and the
    /// checksum.
    ///
    /// # Errors
    /// The first thing found wrong.
    pub fn new<P: SavedPrimitive>(
        bytes: &'a [u8],
        kind: &str,
        layout: u32,
    ) -> Result<Self, LoadError> {
        check_header::<P>(bytes, kind, layout)?;
        let entries = self::layout(bytes, bytes.len() as u64)?;
        let mut covered = HEADER + ENTRY * entries.len();
        for e in &entries {
            if bytes[covered..e.at].iter().any(|&b| b != 0) {
                return Err(LoadError::Checksum);
            }
            covered = e.at + e.len;
        }
        if bytes[covered..].iter().any(|&b| b != 0) || file_checksum(bytes) != u64_at(bytes, 88) {
            return Err(LoadError::Checksum);
        }
        let sums = vec![None; entries.len()];
        Ok(Self {
            head: bytes[..HEADER + ENTRY * entries.len()].to_vec(),
            source: Source::Bytes(bytes),
            entries,
            sums: std::sync::Mutex::new(sums),
        })
    }

    /// Opens the file at `path` as a file of structure `kind` (layout version `layout`) over
    /// primitives `P` and checks its header and section table; the sections are read when
    /// asked for, the checksum checked by [`finish`](Reader::finish).
    ///
    /// # Errors
    /// [`LoadError::Io`] when the file cannot be read, else the first thing found wrong.
    pub fn open<P: SavedPrimitive>(
        path: &Path,
        kind: &str,
        layout: u32,
    ) -> Result<Reader<'static>, LoadError> {
        let io = |e: std::io::Error| LoadError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let file_len = file.metadata().map_err(io)?.len();
        let mut head = vec![0u8; (HEADER as u64).min(file_len) as usize];
        read_at(&file, &mut head, 0).map_err(io)?;
        check_header::<P>(&head, kind, layout)?;
        let count = (u32_at(&head, 80) as usize).min(MAX_SECTIONS);
        let table = ((HEADER + ENTRY * count) as u64).min(file_len) as usize;
        head.resize(table, 0);
        read_at(&file, &mut head[HEADER..], HEADER as u64).map_err(io)?;
        let entries = self::layout(&head, file_len)?;
        Ok(Reader {
            source: Source::File(file),
            sums: std::sync::Mutex::new(vec![None; entries.len()]),
            entries,
            head,
        })
    }

    /// The elements of section `tag`, copied out (so the file's bytes need no alignment).
    ///
    /// # Errors
    /// [`LoadError::Malformed`] when there is no such section, its elements are not `T`'s size
    /// or a file cannot be read.
    pub fn section<T: Pod>(&self, tag: &str) -> Result<Vec<T>, LoadError> {
        let key = tag_of(tag);
        let Some(k) = self.entries.iter().position(|e| e.tag == key) else {
            return Err(LoadError::Malformed(format!("no section `{tag}`")));
        };
        let e = self.entries[k];
        if e.size != std::mem::size_of::<T>() {
            return Err(LoadError::Malformed(format!(
                "section `{tag}` has {}-byte elements, not {}",
                e.size,
                std::mem::size_of::<T>()
            )));
        }
        let mut out: Vec<T> = bytemuck::zeroed_vec(e.len / e.size);
        let sum = self.fill(e, bytemuck::cast_slice_mut(&mut out))?;
        if let Ok(mut sums) = self.sums.lock() {
            sums[k] = Some(sum);
        }
        Ok(out)
    }

    /// Reads section `e` into `out` (its length), block by block on the builders' threads,
    /// and returns its checksum.
    fn fill(&self, e: Entry, out: &mut [u8]) -> Result<u64, LoadError> {
        // PERF: the 606 MB file of the 10M-triangle terrain's BVH took 0.35 s to read whole
        // and 0.27 s more to copy into the tree's arrays; read straight into them, a block per
        // task on two threads with each block's checksum taken while it is in cache, 0.19 s
        // (`cargo bench -p rt-benches --bench saved`).
        let blocks = rt_core::par::map_chunks_mut_indexed(out, BLOCK, |k, block| {
            let at = e.at + k * BLOCK;
            match &self.source {
                Source::Bytes(bytes) => block.copy_from_slice(&bytes[at..at + block.len()]),
                Source::File(file) => read_at(file, block, at as u64)?,
            }
            Ok(checksum(block))
        });
        let blocks: Result<Vec<u64>, std::io::Error> = blocks.into_iter().collect();
        blocks
            .map(|b| fold_blocks(e.len, b))
            .map_err(|err| LoadError::Malformed(format!("the file cannot be read: {err}")))
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

    /// The `N` elements of section `tag`, such as a structure's fixed list of counts and flags.
    ///
    /// # Errors
    /// As [`section`](Reader::section), and when the section does not hold exactly `N`
    /// elements.
    pub fn array<T: Pod, const N: usize>(&self, tag: &str) -> Result<[T; N], LoadError> {
        let all = self.section::<T>(tag)?;
        let found = all.len();
        <[T; N]>::try_from(all).map_err(|_| {
            LoadError::Malformed(format!("section `{tag}` holds {found} values, not {N}"))
        })
    }

    /// For a file, reads the sections not asked for, checks that the padding between sections
    /// is zero and compares the file's checksum with the one it records (bytes were checked by
    /// [`new`](Reader::new) already).
    ///
    /// # Errors
    /// [`LoadError::Checksum`] when they differ; [`LoadError::Malformed`] when a file cannot be
    /// read.
    pub fn finish(self) -> Result<(), LoadError> {
        let Source::File(file) = &self.source else {
            return Ok(());
        };
        let unreadable =
            |err: std::io::Error| LoadError::Malformed(format!("the file cannot be read: {err}"));
        let known = self.sums.lock().map(|s| s.clone()).unwrap_or_default();
        let mut sums = Vec::with_capacity(self.entries.len());
        let mut covered = self.head.len();
        let mut scratch = Vec::new();
        for (k, e) in self.entries.iter().enumerate() {
            let mut gap = vec![0u8; e.at - covered];
            read_at(file, &mut gap, covered as u64).map_err(unreadable)?;
            if gap.iter().any(|&b| b != 0) {
                return Err(LoadError::Checksum);
            }
            covered = e.at + e.len;
            match known.get(k).copied().flatten() {
                Some(sum) => sums.push(sum),
                None => {
                    scratch.resize(e.len, 0);
                    sums.push(self.fill(*e, &mut scratch)?);
                }
            }
        }
        let mut tail = vec![0u8; covered.next_multiple_of(ALIGN) - covered];
        read_at(file, &mut tail, covered as u64).map_err(unreadable)?;
        let sum = combine(&self.head[..HEADER], &self.head[HEADER..], sums);
        if tail.iter().any(|&b| b != 0) || sum != u64_at(&self.head, 88) {
            return Err(LoadError::Checksum);
        }
        Ok(())
    }
}

impl fmt::Debug for Reader<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sections: Vec<String> = self
            .entries
            .iter()
            .map(|e| format!("{} ({} bytes)", name_of(&e.tag), e.len))
            .collect();
        f.debug_struct("Reader")
            .field("sections", &sections)
            .finish()
    }
}

/// Reads exactly `out.len()` bytes of `file` from `at`.
#[cfg(unix)]
fn read_at(file: &std::fs::File, out: &mut [u8], at: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, out, at)
}

/// Reads exactly `out.len()` bytes of `file` from `at`.
#[cfg(not(unix))]
fn read_at(file: &std::fs::File, out: &mut [u8], at: u64) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    // A handle of its own: threads reading blocks at once would move one shared cursor under
    // each other.
    let mut f = file.try_clone()?;
    f.seek(SeekFrom::Start(at))?;
    f.read_exact(out)
}

/// A built structure that can be saved to a file and loaded back.
///
/// A structure says which sections it writes ([`write_sections`](Persist::write_sections)),
/// how it reads them back ([`read_sections`](Persist::read_sections), rebuilding nothing) and
/// what it checks before answering a query ([`check_loaded`](Persist::check_loaded), its
/// `validate`); the provided methods do the rest. A loaded structure answers every query bit
/// for bit as the saved one did: the conformance kit checks this for every structure. What
/// depends on the machine rather than the structure (the SIMD kernels a BVH traces with) is
/// chosen again on load.
///
/// ```
/// use rt_persist::Persist;
/// # fn demo<A: Persist>(built: &A) -> Result<(), rt_persist::LoadError> {
/// let bytes = built.save();
/// let loaded = A::load(&bytes)?;
/// # let _ = loaded; Ok(()) }
/// ```
pub trait Persist: Sized {
    /// The structure's kind as the file records it, for example `rt-bvh::Bvh`.
    const KIND: &'static str;
    /// The version of the structure's own sections; a file of another version is refused
    /// with [`LoadError::Version`].
    const LAYOUT: u32;
    /// The primitive type the file records.
    type Saved: SavedPrimitive;

    /// Adds the structure's sections to `w`.
    fn write_sections<'a>(&'a self, w: &mut Writer<'a>);

    /// The structure from its sections, not yet checked.
    ///
    /// # Errors
    /// A section missing, of the wrong size, or holding a value out of range.
    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError>;

    /// Checks every invariant the structure's queries rely on (its `validate`), on a structure
    /// whose file passed its checksum.
    ///
    /// # Errors
    /// [`LoadError::Invalid`] naming the first broken invariant.
    fn check_loaded(&self) -> Result<(), LoadError>;

    /// The file's bytes.
    fn save(&self) -> Vec<u8> {
        let mut w = Writer::new::<Self::Saved>(Self::KIND, Self::LAYOUT);
        self.write_sections(&mut w);
        w.finish()
    }

    /// Writes the file to `path`, each section straight from the structure's memory.
    ///
    /// # Errors
    /// When the file cannot be written.
    fn save_file(&self, path: &Path) -> std::io::Result<()> {
        let mut w = Writer::new::<Self::Saved>(Self::KIND, Self::LAYOUT);
        self.write_sections(&mut w);
        let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
        w.write_to(&mut out)?;
        std::io::Write::flush(&mut out)
    }

    /// The structure saved in `bytes`, checked: the framing and checksum by [`Reader`], then
    /// [`check_loaded`](Persist::check_loaded).
    ///
    /// # Errors
    /// The first thing found wrong, never a panic.
    fn load(bytes: &[u8]) -> Result<Self, LoadError> {
        let r = Reader::new::<Self::Saved>(bytes, Self::KIND, Self::LAYOUT)?;
        let loaded = Self::read_sections(&r)?;
        r.finish()?;
        loaded.check_loaded()?;
        Ok(loaded)
    }

    /// [`load`](Persist::load) from the file at `path`, each section read straight into the
    /// array it becomes; every error names the file.
    ///
    /// # Errors
    /// As [`load`](Persist::load), inside [`LoadError::InFile`], or [`LoadError::Io`].
    fn load_file(path: &Path) -> Result<Self, LoadError> {
        let in_file = |error: LoadError| match error {
            LoadError::Io { .. } => error,
            error => LoadError::InFile {
                path: path.to_path_buf(),
                error: Box::new(error),
            },
        };
        let r = Reader::open::<Self::Saved>(path, Self::KIND, Self::LAYOUT).map_err(in_file)?;
        let loaded = Self::read_sections(&r).map_err(in_file)?;
        r.finish().map_err(in_file)?;
        loaded.check_loaded().map_err(in_file)?;
        Ok(loaded)
    }
}

/// The reference saves its valid primitives and their input indices (sections `prims` and
/// `ids`); loading checks that every primitive is valid and the indices strictly increase, and
/// computes the box again.
impl<P: SavedPrimitive> Persist for rt_core::BruteForce<P> {
    const KIND: &'static str = "rt-core::BruteForce";
    const LAYOUT: u32 = 1;
    type Saved = P;

    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        w.section("prims", self.prims());
        w.section("ids", self.ids());
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let (prims, ids): (Vec<P>, Vec<u32>) = (r.section("prims")?, r.section("ids")?);
        Ok(Self::from_parts(prims, ids))
    }

    fn check_loaded(&self) -> Result<(), LoadError> {
        let invalid = |m: String| Err(LoadError::Invalid(rt_core::ValidationError::new(m)));
        let (prims, ids) = (self.prims(), self.ids());
        if prims.len() != ids.len() {
            return invalid(format!("{} primitives but {} ids", prims.len(), ids.len()));
        }
        if let Some(i) = prims.iter().position(|p| !p.is_valid()) {
            return invalid(format!("primitive {i} is not valid"));
        }
        if let Some(i) = ids.windows(2).position(|w| w[0] >= w[1]) {
            return invalid(format!("ids {} and {} do not increase", ids[i], ids[i + 1]));
        }
        Ok(())
    }
}

/// A count or index stored as `u64`, read back as `usize`.
///
/// # Errors
/// [`LoadError::Malformed`] when it does not fit this machine's `usize`.
pub fn to_usize(value: u64, what: &str) -> Result<usize, LoadError> {
    usize::try_from(value)
        .map_err(|_| LoadError::Malformed(format!("{what} {value} does not fit in memory")))
}

/// A count stored as `u64`, read back as `u32`.
///
/// # Errors
/// [`LoadError::Malformed`] when it does not fit.
pub fn to_u32(value: u64, what: &str) -> Result<u32, LoadError> {
    u32::try_from(value).map_err(|_| LoadError::Malformed(format!("{what} {value} is too large")))
}

/// A flag stored as `u32`: 0 or 1, anything else refused.
///
/// # Errors
/// [`LoadError::Malformed`] for any other value.
pub fn to_bool(value: u32, what: &str) -> Result<bool, LoadError> {
    match value {
        0 => Ok(false),
        1 => Ok(true),
        other => Err(LoadError::Malformed(format!(
            "{what} is {other}, not 0 or 1"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::{Accel, Sphere, Triangle};

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
        let mut rng = rt_core::Rng::new(5);
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

    /// A scratch file of this test process.
    fn scratch(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("rt-core-persist-{}-{name}", std::process::id()))
    }

    /// Written to a file, read from it: the same sections, a section larger than a block (so
    /// its checksum folds several), the same bytes as `finish`, and the checksum checked.
    #[test]
    fn files_read_back_as_written_and_damage_is_found_by_finish() {
        let big: Vec<u32> = (0..(3 * BLOCK / 4 + 5) as u32).collect();
        let write = |w: &mut Writer<'_>| {
            w.section("nodes", &[1u32, 2, 3]);
            w.section_owned("big", big.clone());
        };
        let mut w = Writer::new::<Triangle>("test::Thing", 3);
        write(&mut w);
        let bytes = w.finish();
        let path = scratch("roundtrip");
        let mut w = Writer::new::<Triangle>("test::Thing", 3);
        write(&mut w);
        w.write_to(&mut std::fs::File::create(&path).unwrap())
            .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
        let r = Reader::open::<Triangle>(&path, "test::Thing", 3).unwrap();
        assert_eq!(r.section::<u32>("big").unwrap(), big);
        r.finish().unwrap(); // `nodes` was not asked for: finish reads it for the checksum
        let from_bytes = Reader::new::<Triangle>(&bytes, "test::Thing", 3).unwrap();
        assert_eq!(from_bytes.section::<u32>("nodes").unwrap(), [1, 2, 3]);

        // A bit flipped in a section, in the padding after it, or in the table.
        let big_at = bytes.len() - 4 * big.len() - 4;
        for at in [
            HEADER + ENTRY * 2 + 20,
            big_at + 8,
            bytes.len() - 1,
            HEADER + 4,
        ] {
            let mut damaged = bytes.clone();
            damaged[at] ^= 0x10;
            std::fs::write(&path, &damaged).unwrap();
            let e = Reader::open::<Triangle>(&path, "test::Thing", 3).and_then(|r| {
                let _ = r.section::<u32>("big");
                r.finish()
            });
            assert!(e.is_err(), "a flip at {at} went unnoticed");
            assert!(Reader::new::<Triangle>(&damaged, "test::Thing", 3).is_err());
        }
        // Cut short: refused by the table's check, before any section is read.
        std::fs::write(&path, &bytes[..bytes.len() - 16]).unwrap();
        assert!(matches!(
            Reader::open::<Triangle>(&path, "test::Thing", 3),
            Err(LoadError::Malformed(_))
        ));
        let _ = std::fs::remove_file(&path);
    }

    /// `load_file` names the file in every error; a missing file is an I/O error.
    #[test]
    fn load_file_names_the_file() {
        type Brute = rt_core::BruteForce<Triangle>;
        let missing = scratch("missing");
        let e = Brute::load_file(&missing).unwrap_err();
        assert!(matches!(e, LoadError::Io { .. }), "{e}");
        assert!(e.to_string().contains("missing"), "{e}");
        let path = scratch("sphere-brute");
        let spheres = [rt_core::Sphere::new(rt_core::glam::Vec3::ZERO, 1.0)];
        rt_core::BruteForce::build(&spheres, &())
            .save_file(&path)
            .unwrap();
        let e = Brute::load_file(&path).unwrap_err();
        assert!(
            matches!(&e, LoadError::InFile { error, .. } if matches!(**error, LoadError::Mismatch { .. })),
            "{e}"
        );
        assert!(
            e.to_string().starts_with(&path.display().to_string()),
            "{e}"
        );
        let loaded = rt_core::BruteForce::<rt_core::Sphere>::load_file(&path).unwrap();
        assert_eq!(
            loaded.save(),
            rt_core::BruteForce::build(&spheres, &()).save()
        );
        let _ = std::fs::remove_file(&path);
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
