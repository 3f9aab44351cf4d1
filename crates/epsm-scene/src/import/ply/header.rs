//! The PLY header: format line, elements and their (list) properties, with
//! errors naming the header line. Comments and `obj_info` lines are skipped.
//!
//! | line | meaning |
//! |---|---|
//! | `ply` | magic, first line |
//! | `format ascii` / `binary_little_endian` / `binary_big_endian` `1.0` | body encoding |
//! | `element NAME COUNT` | an element |
//! | `property TYPE NAME`, `property list COUNT_TYPE TYPE NAME` | its properties |
//! | `end_header` | end of the header |
//!
//! ```text
//! ply
//! format ascii 1.0
//! element vertex 3
//! property float x
//! ```

/// How the body is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Text.
    Ascii,
    /// `binary_little_endian`.
    Little,
    /// `binary_big_endian`.
    Big,
}

/// A scalar type of the header, by its size in bytes and kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `char`, `int8`.
    I8,
    /// `uchar`, `uint8`.
    U8,
    /// `short`, `int16`.
    I16,
    /// `ushort`, `uint16`.
    U16,
    /// `int`, `int32`.
    I32,
    /// `uint`, `uint32`.
    U32,
    /// `float`, `float32`.
    F32,
    /// `double`, `float64`.
    F64,
}

impl Scalar {
    /// The type called `name` in a header.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Size in bytes in a binary body.
    pub fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

/// One property: a scalar, or a list with its count type.
#[derive(Clone, Debug)]
pub struct Property {
    /// Property name.
    pub name: String,
    /// The scalar type (of the items, for a list).
    pub value: Scalar,
    /// The count type of a list.
    pub list_count: Option<Scalar>,
}

/// One element: its name, item count and properties.
#[derive(Clone, Debug)]
pub struct Element {
    /// Element name (`vertex`, `face`, …).
    pub name: String,
    /// Declared number of items.
    pub count: usize,
    /// Properties in file order.
    pub properties: Vec<Property>,
}

/// The parsed header.
pub struct Header {
    /// Body encoding.
    pub format: Format,
    /// Elements in file order.
    pub elements: Vec<Element>,
}

/// The header and the body after it; errors are `(line, message)`.
pub fn header(bytes: &[u8]) -> Result<(Header, &[u8]), (usize, String)> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err((
            1,
            "not a PLY file (the first line must be \"ply\")".to_owned(),
        ));
    }
    let end = find(bytes, b"end_header").ok_or((1, "no end_header line".to_owned()))?;
    let body_start = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| end + i + 1);
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| (1, "header is not text".into()))?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |msg: &str| (line_no, format!("{msg}: \"{}\"", line.trim()));
        match words.as_slice() {
            ["ply"] if i == 0 => {}
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", kind, "1.0"] => {
                format = Some(match *kind {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(bad("unknown format")),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: (*name).to_owned(),
                count: count.parse().map_err(|_| bad("expected a count"))?,
                properties: Vec::new(),
            }),
            ["property", rest @ ..] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let scalar = |t: &str| Scalar::parse(t).ok_or_else(|| bad("unknown type"));
                let property = match rest {
                    ["list", count, value, name] => Property {
                        name: (*name).to_owned(),
                        value: scalar(value)?,
                        list_count: Some(scalar(count)?),
                    },
                    [value, name] => Property {
                        name: (*name).to_owned(),
                        value: scalar(value)?,
                        list_count: None,
                    },
                    _ => return Err(bad("malformed property")),
                };
                element.properties.push(property);
            }
            _ => return Err(bad("unexpected header line")),
        }
    }
    let format = format.ok_or((1, "no format line".to_owned()))?;
    Ok((Header { format, elements }, &bytes[body_start..]))
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}
