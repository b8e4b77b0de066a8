//! The structure of a MATLAB Level-5 MAT-file: its numeric variables, parsed from untrusted
//! bytes with every size checked.
//!
//! Facts from MathWorks, "MAT-File Format" (R2019a), chapter 1 ("Level 5 MAT-File Format"):
//!
//! - a 128-byte header: 116 bytes of text, 8 bytes of subsystem-data offset, a 16-bit version
//!   (0x0100) and the endian indicator: the characters `MI` written as a 16-bit value, so
//!   that a reader sees `IM` in a little-endian file and `MI` in a big-endian one;
//! - then data elements, each an 8-byte tag (32-bit data type, 32-bit number of bytes) and its
//!   data, padded to a multiple of 8 bytes; a *small data element* (at most 4 bytes of data)
//!   packs the number of bytes into the upper 16 bits and the type into the lower 16 bits of
//!   the tag's first word, with the data in its second word;
//! - data types: miINT8 1, miUINT8 2, miINT16 3, miUINT16 4, miINT32 5, miUINT32 6,
//!   miSINGLE 7, miDOUBLE 9, miINT64 12, miUINT64 13, miMATRIX 14, miCOMPRESSED 15 (a zlib
//!   stream holding one data element; not padded), miUTF8 16, miUTF16 17, miUTF32 18;
//! - a numeric array (miMATRIX) holds subelements: array flags (miUINT32, two words; the
//!   class in the lowest byte of the first, the complex flag 0x0800), dimensions (miINT32,
//!   at least two), the array name (miINT8), the real part and, when complex, the imaginary
//!   part, each stored in any numeric data type (MATLAB stores a double array of small
//!   integers as miUINT8, for one), in column-major order;
//! - classes: cell 1, struct 2, object 3, char 4, sparse 5, double 6, single 7, int8 8,
//!   uint8 9, int16 10, uint16 11, int32 12, uint32 13, int64 14, uint64 15.
//!
//! Nothing here trusts a size read from the file: every offset and product is computed with
//! checked arithmetic and compared with the bytes present before it is used, decompressed data
//! is bounded by [`MAX_MAT_BYTES`], and a problem is an error (never a panic, never a print).

use std::borrow::Cow;
use std::ops::Range;

/// Most bytes a MAT-file's compressed variables may decompress to, in total (1 GiB): a larger
/// (or maliciously crafted) file is refused before more is allocated.
pub const MAX_MAT_BYTES: usize = 1 << 30;

/// Most values one variable may hold to be read as a column (2^27, 1 GiB of `f64`).
pub const MAX_MAT_VALUES: usize = 1 << 27;

const HEADER_BYTES: usize = 128;
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;
/// The complex flag of the array flags' first word.
const COMPLEX_FLAG: u32 = 0x0800;
/// The logical flag of the array flags' first word.
const LOGICAL_FLAG: u32 = 0x0200;

/// How the numbers of a variable's real part are stored (the data type of its subelement).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Storage {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
    I64,
    U64,
}

impl Storage {
    fn from_type(data_type: u32) -> Option<Storage> {
        Some(match data_type {
            1 => Storage::I8,
            2 => Storage::U8,
            3 => Storage::I16,
            4 => Storage::U16,
            5 => Storage::I32,
            6 => Storage::U32,
            7 => Storage::F32,
            9 => Storage::F64,
            12 => Storage::I64,
            13 => Storage::U64,
            _ => return None,
        })
    }

    fn bytes(self) -> usize {
        match self {
            Storage::I8 | Storage::U8 => 1,
            Storage::I16 | Storage::U16 => 2,
            Storage::I32 | Storage::U32 | Storage::F32 => 4,
            Storage::F64 | Storage::I64 | Storage::U64 => 8,
        }
    }
}

/// One numeric variable of a MAT-file.
#[derive(Debug)]
pub(super) struct Variable<'a> {
    /// Its name.
    pub name: String,
    /// Its dimensions (at least one).
    pub dims: Vec<usize>,
    /// Its class, as MATLAB names it (`double`, `int16`, `logical`, ...).
    pub class: &'static str,
    /// Whether it has an imaginary part.
    pub complex: bool,
    /// The buffer holding its real part: the file, or a decompressed element.
    buffer: Cow<'a, [u8]>,
    /// Where its real part lies in `buffer`.
    real: Range<usize>,
    storage: Storage,
    little_endian: bool,
}

impl Variable<'_> {
    /// The number of values (the product of the dimensions, checked while parsing).
    pub fn len(&self) -> usize {
        (self.real.end - self.real.start) / self.storage.bytes()
    }

    /// The real part as `f64` in column-major order (integers beyond 2^53 in magnitude are
    /// rounded, as MATLAB's `double()` rounds them).
    pub fn values(&self) -> Vec<f64> {
        let data = &self.buffer[self.real.clone()];
        let little = self.little_endian;
        macro_rules! convert {
            ($t:ty, $n:literal) => {
                data.chunks_exact($n)
                    .map(|chunk| {
                        let mut b = [0u8; $n];
                        b.copy_from_slice(chunk);
                        let x = if little {
                            <$t>::from_le_bytes(b)
                        } else {
                            <$t>::from_be_bytes(b)
                        };
                        x as f64
                    })
                    .collect()
            };
        }
        match self.storage {
            Storage::I8 => convert!(i8, 1),
            Storage::U8 => convert!(u8, 1),
            Storage::I16 => convert!(i16, 2),
            Storage::U16 => convert!(u16, 2),
            Storage::I32 => convert!(i32, 4),
            Storage::U32 => convert!(u32, 4),
            Storage::F32 => convert!(f32, 4),
            Storage::F64 => convert!(f64, 8),
            // Precision beyond 2^53 is lost, as MATLAB's double() loses it.
            Storage::I64 => convert!(i64, 8),
            Storage::U64 => convert!(u64, 8),
        }
    }
}

/// The numeric variables of a Level-5 MAT-file, in file order; other arrays (char, cell,
/// struct, sparse, objects) are skipped. Errors say what is wrong in words for the user.
pub(super) fn parse(bytes: &[u8]) -> Result<Vec<Variable<'_>>, String> {
    parse_with_limit(bytes, MAX_MAT_BYTES)
}

/// [`parse`] with at most `limit` bytes decompressed in total.
fn parse_with_limit(bytes: &[u8], limit: usize) -> Result<Vec<Variable<'_>>, String> {
    let little_endian = match bytes.get(126..HEADER_BYTES) {
        Some(b"IM") => true,
        Some(b"MI") => false,
        _ => return Err("the file has no MAT-file header".to_owned()),
    };
    let mut variables = Vec::new();
    let mut decompressed_total = 0usize;
    let mut at = HEADER_BYTES;
    while at < bytes.len() {
        let tag = Tag::read(bytes, at, little_endian).ok_or_else(|| truncated(bytes, at, 8))?;
        let Some(size) = tag.size else {
            // A small data element at the top level: nothing a variable can be.
            at += 8;
            continue;
        };
        let start = at + 8;
        let padded = if tag.data_type == MI_COMPRESSED {
            size
        } else {
            pad8(size).ok_or_else(|| truncated(bytes, at, usize::MAX))?
        };
        let end = start
            .checked_add(padded)
            .filter(|&end| end <= bytes.len())
            .ok_or_else(|| truncated(bytes, at, padded.saturating_add(8)))?;
        let content = start..start + size;
        match tag.data_type {
            MI_MATRIX => {
                if let Some(v) = matrix(Cow::Borrowed(bytes), content, little_endian)
                    .map_err(|e| format!("the variable stored at byte {at}: {e}"))?
                {
                    variables.push(v);
                }
            }
            MI_COMPRESSED => {
                let budget = limit.saturating_sub(decompressed_total);
                let inflated = inflate(&bytes[content], budget, limit)
                    .map_err(|e| format!("the compressed variable stored at byte {at}: {e}"))?;
                decompressed_total += inflated.len();
                if let Some(v) = compressed_matrix(inflated, little_endian)
                    .map_err(|e| format!("the compressed variable stored at byte {at}: {e}"))?
                {
                    variables.push(v);
                }
            }
            // Anything else at the top level is not a variable: skipped.
            _ => {}
        }
        at = end;
    }
    Ok(variables)
}

/// The message for an element at `at` that needs `needed` bytes the file does not have.
fn truncated(bytes: &[u8], at: usize, needed: usize) -> String {
    let needed = if needed == usize::MAX {
        "more".to_owned()
    } else {
        needed.to_string()
    };
    format!(
        "the file is truncated or damaged: the variable stored at byte {at} needs {needed} bytes \
         but the file ends after {}; copy it again from its source, or save it again with \
         save(..., '-v7')",
        bytes.len() - at
    )
}

/// `n` rounded up to a multiple of 8, `None` on overflow.
fn pad8(n: usize) -> Option<usize> {
    n.checked_add(7).map(|m| m / 8 * 8)
}

/// A data element's tag.
#[derive(Debug, Clone, Copy)]
struct Tag {
    data_type: u32,
    /// The number of bytes of a normal element; `None` for a small data element (whose data
    /// is in the tag's second word: see [`Tag::small_len`]).
    size: Option<usize>,
    small_len: usize,
}

impl Tag {
    /// The tag at `at`, or `None` when fewer than 8 bytes are left.
    fn read(bytes: &[u8], at: usize, little: bool) -> Option<Tag> {
        let first = word(bytes, at, little)?;
        let second = word(bytes, at.checked_add(4)?, little)?;
        Some(if first >> 16 != 0 {
            Tag {
                data_type: first & 0xffff,
                size: None,
                small_len: (first >> 16) as usize,
            }
        } else {
            Tag {
                data_type: first,
                size: Some(second as usize),
                small_len: 0,
            }
        })
    }
}

/// The 32-bit word at `at`.
fn word(bytes: &[u8], at: usize, little: bool) -> Option<u32> {
    let b: [u8; 4] = bytes.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(if little {
        u32::from_le_bytes(b)
    } else {
        u32::from_be_bytes(b)
    })
}

/// Decompresses a zlib stream to at most `budget` bytes (what is left of `limit`).
fn inflate(data: &[u8], budget: usize, limit: usize) -> Result<Vec<u8>, String> {
    use miniz_oxide::inflate::TINFLStatus;
    miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(data, budget).map_err(|e| {
        match e.status {
            TINFLStatus::HasMoreOutput => format!(
                "it decompresses to more than {limit} bytes ({} MiB) with the variables before \
                 it, the most a MAT-file may hold here; export the columns you need as CSV, or \
                 save fewer samples per file",
                limit >> 20
            ),
            TINFLStatus::FailedCannotMakeProgress => {
                "the compressed data is truncated or damaged (it ends early); copy the file \
                 again from its source, or save it again with save(..., '-v7')"
                    .to_owned()
            }
            _ => "the compressed data is damaged (it does not decompress); save the file again \
                  with save(..., '-v7')"
                .to_owned(),
        }
    })
}

/// The variable a decompressed element holds, when it is a numeric array.
fn compressed_matrix(inflated: Vec<u8>, little: bool) -> Result<Option<Variable<'static>>, String> {
    let tag = Tag::read(&inflated, 0, little)
        .ok_or_else(|| "the decompressed data is shorter than a tag".to_owned())?;
    let Some(size) = tag.size else {
        return Ok(None);
    };
    if tag.data_type != MI_MATRIX {
        return Ok(None);
    }
    let end = size
        .checked_add(8)
        .filter(|&end| end <= inflated.len())
        .ok_or_else(|| {
            format!(
                "the decompressed data holds {} bytes but the array claims {size}; the file is \
                 damaged: save it again with save(..., '-v7')",
                inflated.len().saturating_sub(8)
            )
        })?;
    matrix(Cow::Owned(inflated), 8..end, little)
}

/// A subelement of an array: its data type and where its data lies.
fn subelement(
    buffer: &[u8],
    at: &mut usize,
    end: usize,
    little: bool,
    what: &str,
) -> Result<(u32, Range<usize>), String> {
    let missing = || format!("the array ends before its {what}; the file is damaged");
    if at.checked_add(8).is_none_or(|e| e > end) {
        return Err(missing());
    }
    let tag = Tag::read(buffer, *at, little).ok_or_else(missing)?;
    match tag.size {
        None => {
            if tag.small_len > 4 {
                return Err(format!(
                    "its {what} claims {} bytes in a small data element (at most 4); the file \
                     is damaged",
                    tag.small_len
                ));
            }
            let data = *at + 4..*at + 4 + tag.small_len;
            *at += 8;
            Ok((tag.data_type, data))
        }
        Some(size) => {
            let start = *at + 8;
            let data_end = start
                .checked_add(size)
                .filter(|&e| e <= end)
                .ok_or_else(|| {
                    format!(
                        "its {what} claims {size} bytes, more than the array holds; the file \
                         is damaged"
                    )
                })?;
            // The padding of the last subelement may be left out.
            *at = pad8(size)
                .and_then(|p| start.checked_add(p))
                .map_or(end, |next| next.min(end));
            Ok((tag.data_type, start..data_end))
        }
    }
}

/// The class name of an array class number, for numeric classes only.
fn numeric_class(class: u32, logical: bool) -> Option<&'static str> {
    Some(match class {
        _ if logical && (6..=15).contains(&class) => "logical",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        _ => return None,
    })
}

/// The numeric array whose subelements lie at `content` of `buffer`; `None` for other arrays.
fn matrix<'a>(
    buffer: Cow<'a, [u8]>,
    content: Range<usize>,
    little: bool,
) -> Result<Option<Variable<'a>>, String> {
    let (mut at, end) = (content.start, content.end);
    if end == at {
        // An empty miMATRIX (MATLAB writes one for an empty cell element).
        return Ok(None);
    }
    let (flags_type, flags) = subelement(&buffer, &mut at, end, little, "array flags")?;
    if flags_type != MI_UINT32 || flags.len() < 8 {
        return Err("its array flags are not two 32-bit words; the file is damaged".to_owned());
    }
    let flags_word = word(&buffer, flags.start, little).unwrap_or(0);
    let class_number = flags_word & 0xff;
    let Some(class) = numeric_class(class_number, flags_word & LOGICAL_FLAG != 0) else {
        return Ok(None);
    };
    let complex = flags_word & COMPLEX_FLAG != 0;

    let (dims_type, dims_range) = subelement(&buffer, &mut at, end, little, "dimensions")?;
    if dims_type != MI_INT32 || dims_range.is_empty() || dims_range.len() % 4 != 0 {
        return Err("its dimensions are not 32-bit integers; the file is damaged".to_owned());
    }
    let mut dims = Vec::with_capacity(dims_range.len() / 4);
    for at in dims_range.step_by(4) {
        let raw = word(&buffer, at, little).unwrap_or(0) as i32;
        let dim = usize::try_from(raw)
            .map_err(|_| format!("it has a negative dimension ({raw}); the file is damaged"))?;
        dims.push(dim);
    }
    let elements = dims
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| {
            format!(
                "its dimensions {} multiply beyond any possible size; the file is damaged",
                super::error::shape_text(&dims)
            )
        })?;

    let (name_type, name_range) = subelement(&buffer, &mut at, end, little, "name")?;
    if !matches!(name_type, MI_INT8 | MI_UINT8 | MI_UTF8) {
        return Err("its name is not text; the file is damaged".to_owned());
    }
    let name = String::from_utf8_lossy(&buffer[name_range]).into_owned();

    let (real_type, real) = subelement(&buffer, &mut at, end, little, "values")?;
    let storage = Storage::from_type(real_type).ok_or_else(|| {
        format!("variable \"{name}\" stores its values as data type {real_type}, which is not a number type; the file is damaged")
    })?;
    if real.len() % storage.bytes() != 0 || real.len() / storage.bytes() != elements {
        return Err(format!(
            "variable \"{name}\" has {} bytes of values for dimensions {} ({elements} values \
             of {} bytes), so the file is damaged; save it again with save(..., '-v7')",
            real.len(),
            super::error::shape_text(&dims),
            storage.bytes()
        ));
    }
    Ok(Some(Variable {
        name,
        dims,
        class,
        complex,
        buffer,
        real,
        storage,
        little_endian: little,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian file holding one compressed element of `inner` (stored deflate blocks).
    fn compressed_file(inner: &[u8]) -> Vec<u8> {
        let mut bytes = vec![b' '; 116];
        bytes.extend_from_slice(&[0; 8]);
        bytes.extend_from_slice(&0x0100u16.to_le_bytes());
        bytes.extend_from_slice(b"IM");
        let stream = miniz_oxide::deflate::compress_to_vec_zlib(inner, 1);
        bytes.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
        bytes.extend_from_slice(&(stream.len() as u32).to_le_bytes());
        bytes.extend_from_slice(&stream);
        bytes
    }

    /// An uncompressed miMATRIX element of `n` zero doubles named `x`.
    fn matrix_element(n: usize) -> Vec<u8> {
        let mut body = Vec::new();
        let mut sub = |data_type: u32, data: &[u8]| {
            body.extend_from_slice(&data_type.to_le_bytes());
            body.extend_from_slice(&(data.len() as u32).to_le_bytes());
            body.extend_from_slice(data);
            body.resize(body.len().div_ceil(8) * 8, 0);
        };
        sub(MI_UINT32, &[6, 0, 0, 0, 0, 0, 0, 0]);
        let dims: Vec<u8> = [n as i32, 1].iter().flat_map(|d| d.to_le_bytes()).collect();
        sub(MI_INT32, &dims);
        sub(MI_INT8, b"x");
        sub(9, &vec![0u8; 8 * n]);
        let mut element = MI_MATRIX.to_le_bytes().to_vec();
        element.extend_from_slice(&(body.len() as u32).to_le_bytes());
        element.extend_from_slice(&body);
        element
    }

    #[test]
    fn decompression_stops_at_the_limit_before_allocating_more() {
        let file = compressed_file(&matrix_element(1000));
        let variables = parse_with_limit(&file, 9000).expect("within the limit");
        assert_eq!(variables[0].len(), 1000);
        let error = parse_with_limit(&file, 4096).expect_err("beyond the limit");
        assert!(error.contains("more than 4096 bytes"), "{error}");
    }

    #[test]
    fn damaged_compressed_data_is_an_error() {
        let mut file = compressed_file(&matrix_element(10));
        let last = file.len() - 1;
        file[last] ^= 0xff; // the checksum
        let error = parse(&file).expect_err("a bad checksum");
        assert!(error.contains("damaged"), "{error}");
        let mut file = compressed_file(&matrix_element(10));
        for b in &mut file[140..150] {
            *b = 0xff;
        }
        assert!(parse(&file).is_err());
    }
}
