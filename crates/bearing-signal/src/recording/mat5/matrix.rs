//! One `miMATRIX` body decoded into a [`Value`]: its sub-elements read in order (flags,
//! dimensions, name, then the data of its class), nested structs and cells followed to
//! [`MAX_DEPTH`]. Every count is checked against the bytes that must hold it before anything
//! is reserved for it.

use super::{dims_text, u32_at, Endian, NumericArray, StructArray, Value, MI_MATRIX};

// Data types of numbers and text (the tag's first word).
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_UTF8: u32 = 16;

// Array classes (the low byte of the array flags).
const MX_CELL: u8 = 1;
const MX_STRUCT: u8 = 2;
const MX_OBJECT: u8 = 3;
const MX_CHAR: u8 = 4;
const MX_SPARSE: u8 = 5;
const MX_FUNCTION: u8 = 16;
const MX_OPAQUE: u8 = 17;

const FLAG_COMPLEX: u32 = 0x0800;

/// Deepest nesting of structs and cells followed; deeper is refused (a hostile file could
/// otherwise nest until the stack overflows).
const MAX_DEPTH: usize = 32;
/// Longest struct field name MATLAB writes is 63 characters (plus NUL); this allows any
/// sensible writer and refuses nonsense.
const MAX_FIELD_NAME_LEN: usize = 1024;

/// Where decoding happens: byte order, and the offset of the buffer being decoded (in the
/// file, or in the decompressed data of a compressed element) for messages.
pub(super) struct Context {
    pub(super) endian: Endian,
    pub(super) base: usize,
    pub(super) compressed: bool,
}

/// A problem inside one variable: where, what, and the variable's name once known.
pub(super) struct DecodeError {
    at: usize,
    problem: String,
    pub(super) name: Option<String>,
}

impl DecodeError {
    pub(super) fn describe(&self, ctx: &Context) -> String {
        if ctx.compressed {
            format!(
                "{} (offset {} of its decompressed data)",
                self.problem,
                ctx.base + self.at
            )
        } else {
            format!("{} (at byte {})", self.problem, ctx.base + self.at)
        }
    }
}

fn problem(at: usize, text: impl Into<String>) -> DecodeError {
    DecodeError {
        at,
        problem: text.into(),
        name: None,
    }
}

/// One sub-element: its type, its data and where the data starts in the buffer.
struct Sub<'a> {
    kind: u32,
    data: &'a [u8],
    at: usize,
}

/// Reads the sub-elements of one `miMATRIX` body in order.
struct SubReader<'a> {
    buf: &'a [u8],
    pos: usize,
    end: usize,
    endian: Endian,
    /// Offset of `buf` within the decoded buffer, for messages.
    origin: usize,
}

impl<'a> SubReader<'a> {
    fn new(buf: &'a [u8], end: usize, endian: Endian) -> Self {
        SubReader {
            buf,
            pos: 0,
            end: end.min(buf.len()),
            endian,
            origin: 0,
        }
    }

    fn remaining(&self) -> usize {
        self.end - self.pos
    }

    /// The next sub-element; a small data element (type and size packed in one word, data in
    /// the next four bytes) or a normal one (8-byte tag, data padded to 8 bytes).
    fn next(&mut self) -> Result<Sub<'a>, DecodeError> {
        let at = self.pos;
        let here = self.origin + at;
        let word = u32_at(&self.buf[..self.end], at, self.endian)
            .ok_or_else(|| problem(here, "a sub-element tag is cut off"))?;
        if word >> 16 != 0 {
            let kind = word & 0xFFFF;
            let len = (word >> 16) as usize;
            if len > 4 || at + 8 > self.end {
                return Err(problem(
                    here,
                    format!("a small sub-element claims {len} bytes (at most 4 fit)"),
                ));
            }
            self.pos = at + 8;
            return Ok(Sub {
                kind,
                data: &self.buf[at + 4..at + 4 + len],
                at: here + 4,
            });
        }
        let len = u32_at(&self.buf[..self.end], at + 4, self.endian)
            .ok_or_else(|| problem(here, "a sub-element tag is cut off"))?
            as usize;
        let start = at + 8;
        let stop = start
            .checked_add(len)
            .filter(|&s| s <= self.end)
            .ok_or_else(|| {
                problem(
                    here,
                    format!(
                        "a sub-element of type {word} claims {len} bytes but its variable has only {} left",
                        self.end.saturating_sub(start)
                    ),
                )
            })?;
        self.pos = start
            .checked_add(len.checked_next_multiple_of(8).unwrap_or(len))
            .unwrap_or(self.end)
            .min(self.end);
        Ok(Sub {
            kind: word,
            data: &self.buf[start..stop],
            at: self.origin + start,
        })
    }
}

/// The name of an uncompressed matrix element, read straight from its first sub-elements
/// (for messages about an element that is cut off).
pub(super) fn top_level_name(element: &[u8], endian: Endian) -> Option<String> {
    let size = u32_at(element, 4, endian)? as usize;
    let body = element.get(8..)?;
    let mut r = SubReader::new(body, size.min(body.len()), endian);
    r.next().ok()?; // array flags
    r.next().ok()?; // dimensions
    let name = r.next().ok()?;
    Some(String::from_utf8_lossy(name.data).into_owned())
}

/// Decodes one `miMATRIX` body that starts `origin` bytes into the top-level variable's body:
/// returns its name (empty inside structs and cells) and value.
pub(super) fn decode_matrix(
    body: &[u8],
    origin: usize,
    ctx: &Context,
    depth: usize,
) -> Result<(String, Value), DecodeError> {
    if body.is_empty() {
        // An empty matrix (MATLAB writes `[]` struct fields as a tag with no data).
        return Ok((
            String::new(),
            Value::Numeric(NumericArray {
                dims: vec![0, 0],
                real: Vec::new(),
                complex: false,
            }),
        ));
    }
    if depth > MAX_DEPTH {
        return Err(problem(
            origin,
            format!("structs or cells nested more than {MAX_DEPTH} deep"),
        ));
    }
    let mut r = SubReader::new(body, body.len(), ctx.endian);
    r.origin = origin;
    let flags = r.next()?;
    if flags.kind != MI_UINT32 || flags.data.len() != 8 {
        return Err(problem(
            flags.at,
            "the array flags are not two 32-bit words",
        ));
    }
    let flag_word = u32_at(flags.data, 0, ctx.endian).unwrap_or(0);
    let class = (flag_word & 0xFF) as u8;
    let complex = flag_word & FLAG_COMPLEX != 0;
    if class == MX_FUNCTION || class == MX_OPAQUE {
        // No dimensions sub-element: the name follows the flags.
        let name = r
            .next()
            .map(|s| String::from_utf8_lossy(s.data).into_owned())
            .unwrap_or_default();
        let kind = if class == MX_FUNCTION {
            "function handle"
        } else {
            "MATLAB object (string, table, datetime, ...)"
        };
        return Ok((
            name,
            Value::Other {
                dims: Vec::new(),
                kind,
            },
        ));
    }
    let dims_sub = r.next()?;
    let dims = dimensions(&dims_sub, ctx.endian)?;
    let name_sub = r.next()?;
    if !matches!(name_sub.kind, MI_INT8 | MI_UINT8 | MI_UTF8) {
        return Err(problem(
            name_sub.at,
            format!("the name sub-element has type {}, not text", name_sub.kind),
        ));
    }
    let name = String::from_utf8_lossy(name_sub.data).into_owned();
    let named = |mut e: DecodeError| {
        if e.name.is_none() && !name.is_empty() {
            e.name = Some(name.clone());
        }
        e
    };
    let numel = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| {
            named(problem(
                dims_sub.at,
                format!("its dimensions {} overflow", dims_text(&dims)),
            ))
        })?;
    let value = match class {
        6..=15 => numeric(&mut r, dims, numel, complex, ctx.endian).map_err(named)?,
        MX_STRUCT | MX_OBJECT => {
            if class == MX_OBJECT {
                r.next().map_err(named)?; // the class name
            }
            structure(&mut r, dims, numel, ctx, depth).map_err(named)?
        }
        MX_CELL => cells(&mut r, dims, numel, ctx, depth).map_err(named)?,
        MX_CHAR => Value::Other { dims, kind: "text" },
        MX_SPARSE => Value::Other {
            dims,
            kind: "sparse matrix",
        },
        other => {
            return Err(named(problem(
                flags.at,
                format!("its array class {other} is not a MATLAB class"),
            )))
        }
    };
    Ok((name, value))
}

fn dimensions(sub: &Sub<'_>, endian: Endian) -> Result<Vec<usize>, DecodeError> {
    if sub.kind != MI_INT32 || !sub.data.len().is_multiple_of(4) || sub.data.len() < 8 {
        return Err(problem(
            sub.at,
            "the dimensions are not two or more 32-bit integers",
        ));
    }
    (0..sub.data.len() / 4)
        .map(|k| {
            let d = u32_at(sub.data, 4 * k, endian).unwrap_or(0) as i32;
            usize::try_from(d)
                .map_err(|_| problem(sub.at + 4 * k, format!("a dimension is negative ({d})")))
        })
        .collect()
}

fn numeric(
    r: &mut SubReader<'_>,
    dims: Vec<usize>,
    numel: usize,
    complex: bool,
    endian: Endian,
) -> Result<Value, DecodeError> {
    let real_sub = r.next()?;
    let real = numbers(&real_sub, endian)?;
    if real.len() != numel {
        return Err(problem(
            real_sub.at,
            format!(
                "it holds {} value(s) but its dimensions {} need {numel}",
                real.len(),
                dims_text(&dims)
            ),
        ));
    }
    if complex && r.remaining() == 0 {
        return Err(problem(
            real_sub.at,
            "it is marked complex but has no imaginary part",
        ));
    }
    Ok(Value::Numeric(NumericArray {
        dims,
        real,
        complex,
    }))
}

/// The values of a numeric sub-element as f64. MATLAB may store an array in a smaller type
/// than its class (doubles that are small integers as `miUINT8`), so any numeric type goes.
fn numbers(sub: &Sub<'_>, endian: Endian) -> Result<Vec<f64>, DecodeError> {
    macro_rules! read {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            if !sub.data.len().is_multiple_of(N) {
                return Err(problem(
                    sub.at,
                    format!(
                        "{} bytes of data are not a whole number of {N}-byte values",
                        sub.data.len()
                    ),
                ));
            }
            sub.data
                .chunks_exact(N)
                .map(|c| {
                    let mut b = [0u8; N];
                    b.copy_from_slice(c);
                    (match endian {
                        Endian::Little => <$t>::from_le_bytes(b),
                        Endian::Big => <$t>::from_be_bytes(b),
                    }) as f64
                })
                .collect()
        }};
    }
    Ok(match sub.kind {
        MI_INT8 => read!(i8),
        MI_UINT8 => read!(u8),
        MI_INT16 => read!(i16),
        MI_UINT16 => read!(u16),
        MI_INT32 => read!(i32),
        MI_UINT32 => read!(u32),
        MI_SINGLE => read!(f32),
        MI_DOUBLE => read!(f64),
        MI_INT64 => read!(i64),
        MI_UINT64 => read!(u64),
        other => {
            return Err(problem(
                sub.at,
                format!("its data has type {other}, not a number type"),
            ))
        }
    })
}

/// Struct arrays: field-name length, field names, then one `miMATRIX` per element and field.
fn structure(
    r: &mut SubReader<'_>,
    dims: Vec<usize>,
    numel: usize,
    ctx: &Context,
    depth: usize,
) -> Result<Value, DecodeError> {
    let len_sub = r.next()?;
    let name_len = match numbers(&len_sub, ctx.endian)?.as_slice() {
        [n] if *n >= 1.0 && *n <= MAX_FIELD_NAME_LEN as f64 => *n as usize,
        _ => {
            return Err(problem(
                len_sub.at,
                "the struct's field-name length is not a number from 1 to 1024",
            ))
        }
    };
    let names_sub = r.next()?;
    if names_sub.data.len() % name_len != 0 {
        return Err(problem(
            names_sub.at,
            format!(
                "{} bytes of field names are not a whole number of {name_len}-byte names",
                names_sub.data.len()
            ),
        ));
    }
    let fields: Vec<String> = names_sub
        .data
        .chunks_exact(name_len)
        .map(|c| {
            let end = c.iter().position(|&b| b == 0).unwrap_or(c.len());
            String::from_utf8_lossy(&c[..end]).into_owned()
        })
        .collect();
    // A struct with no fields holds nothing to read, whatever its size; keeping one empty
    // element per index would let a few bytes claim gigabytes.
    if fields.is_empty() {
        return Ok(Value::Other {
            dims,
            kind: "struct with no fields",
        });
    }
    let count = numel.saturating_mul(fields.len());
    // Every field value takes at least an 8-byte tag: more than fits is damage.
    if count > r.remaining() / 8 {
        return Err(problem(
            names_sub.at,
            format!(
                "a {} struct with {} field(s) needs {count} values but its data holds at most {}",
                dims_text(&dims),
                fields.len(),
                r.remaining() / 8
            ),
        ));
    }
    let mut elements = Vec::with_capacity(numel);
    for _ in 0..numel {
        let mut values = Vec::with_capacity(fields.len());
        for field in &fields {
            let value = child(r, ctx, depth).map_err(|mut e| {
                e.problem = format!("field '{field}': {}", e.problem);
                e
            })?;
            values.push(value);
        }
        elements.push(values);
    }
    Ok(Value::Struct(StructArray { fields, elements }))
}

fn cells(
    r: &mut SubReader<'_>,
    dims: Vec<usize>,
    numel: usize,
    ctx: &Context,
    depth: usize,
) -> Result<Value, DecodeError> {
    if numel > r.remaining() / 8 {
        return Err(problem(
            r.origin + r.pos,
            format!(
                "a {} cell array needs {numel} values but its data holds at most {}",
                dims_text(&dims),
                r.remaining() / 8
            ),
        ));
    }
    let mut values = Vec::with_capacity(numel);
    for k in 0..numel {
        values.push(child(r, ctx, depth).map_err(|mut e| {
            e.problem = format!("cell {}: {}", k + 1, e.problem);
            e
        })?);
    }
    Ok(Value::Cell(values))
}

/// A nested `miMATRIX` (a struct field's or a cell's value).
fn child(r: &mut SubReader<'_>, ctx: &Context, depth: usize) -> Result<Value, DecodeError> {
    let sub = r.next()?;
    if sub.kind != MI_MATRIX {
        return Err(problem(
            sub.at,
            format!("a value has type {}, not a MATLAB array", sub.kind),
        ));
    }
    decode_matrix(sub.data, sub.at, ctx, depth + 1).map(|(_, value)| value)
}
