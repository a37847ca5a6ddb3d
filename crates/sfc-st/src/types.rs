//! IEC 61131-3 data types, their generic classes (ANY_NUM, ANY_BIT, …) and the implicit
//! conversions the checker allows.

use std::fmt;

/// A resolved IEC 61131-3 data type.
///
/// Derived types are resolved to their structure: an alias `TYPE Temp : REAL; END_TYPE` is
/// `Real`; structures and enumerations keep their name so that two declarations with equal
/// fields stay distinct types.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Type {
    /// `BOOL`.
    Bool,
    /// `SINT`, 8-bit signed.
    SInt,
    /// `INT`, 16-bit signed.
    Int,
    /// `DINT`, 32-bit signed.
    DInt,
    /// `LINT`, 64-bit signed.
    LInt,
    /// `USINT`, 8-bit unsigned.
    USInt,
    /// `UINT`, 16-bit unsigned.
    UInt,
    /// `UDINT`, 32-bit unsigned.
    UDInt,
    /// `ULINT`, 64-bit unsigned.
    ULInt,
    /// `BYTE`, 8-bit string.
    Byte,
    /// `WORD`, 16-bit string.
    Word,
    /// `DWORD`, 32-bit string.
    DWord,
    /// `LWORD`, 64-bit string.
    LWord,
    /// `REAL`, IEEE 754 single.
    Real,
    /// `LREAL`, IEEE 754 double.
    LReal,
    /// `TIME`, a duration.
    Time,
    /// `LTIME`, a long duration.
    LTime,
    /// `DATE`.
    Date,
    /// `TIME_OF_DAY` (`TOD`).
    TimeOfDay,
    /// `DATE_AND_TIME` (`DT`).
    DateAndTime,
    /// `STRING` or `STRING[len]`.
    String {
        /// Maximum length in characters; `None` for the implementation default.
        len: Option<u32>,
    },
    /// `WSTRING` or `WSTRING[len]`.
    WString {
        /// Maximum length in characters; `None` for the implementation default.
        len: Option<u32>,
    },
    /// `ARRAY [lo..hi, …] OF elem`; one `(lo, hi)` per dimension.
    Array {
        /// `(lo, hi)` of each dimension, inclusive.
        dims: Vec<(i64, i64)>,
        /// The element type.
        elem: Box<Type>,
    },
    /// A structure; `name` is `None` for an anonymous `STRUCT … END_STRUCT` in a declaration.
    Struct {
        /// The declared name, if any.
        name: Option<String>,
        /// Fields in declaration order.
        fields: Vec<(String, Type)>,
    },
    /// An enumeration: values with their ordinals; `base` for typed enums `INT (A := 1)`.
    Enum {
        /// The declared name, if any.
        name: Option<String>,
        /// The integer base type of a typed enumeration.
        base: Option<Box<Type>>,
        /// Values in declaration order with their ordinals.
        values: Vec<(String, i64)>,
    },
    /// An integer subrange `base (lo..hi)`.
    Subrange {
        /// The integer type the range restricts.
        base: Box<Type>,
        /// Smallest allowed value.
        lo: i64,
        /// Largest allowed value.
        hi: i64,
    },
    /// An instance of a function block (standard or user); the type name, upper-case.
    FunctionBlock(String),
    /// A variable of an interface type (`INTERFACE I_Cyl`, IEC 61131-3 3rd edition): it designates
    /// an instance of a block that implements the interface, `0` for none; the name, upper-case.
    Interface(String),
    /// `POINTER TO T` (CODESYS): the address of a `T`, `0` for none; `p^` is the `T`.
    Pointer(Box<Type>),
    /// `REFERENCE TO T` (CODESYS) or `REF_TO T`: an alias of a `T`, set by `r REF= x`; read and
    /// written, it is that `T`.
    Reference(Box<Type>),
    /// The type of an erroneous expression: a diagnostic was already reported, and every
    /// operation involving it is accepted silently so one mistake gives one message.
    Error,
}

/// A generic type class of the standard (IEC 61131-3 table 11), used by the signatures of
/// standard functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Generic {
    /// `ANY`: every type.
    Any,
    /// `ANY_ELEMENTARY`.
    AnyElementary,
    /// `ANY_MAGNITUDE`: numbers and durations.
    AnyMagnitude,
    /// `ANY_NUM`: integers and reals.
    AnyNum,
    /// `ANY_REAL`.
    AnyReal,
    /// `ANY_INT`.
    AnyInt,
    /// `ANY_BIT`: BOOL and bit strings.
    AnyBit,
    /// `ANY_STRING`.
    AnyString,
    /// `ANY_DATE`.
    AnyDate,
}

impl Generic {
    /// The IEC name, e.g. `ANY_NUM`.
    pub fn name(self) -> &'static str {
        match self {
            Generic::Any => "ANY",
            Generic::AnyElementary => "ANY_ELEMENTARY",
            Generic::AnyMagnitude => "ANY_MAGNITUDE",
            Generic::AnyNum => "ANY_NUM",
            Generic::AnyReal => "ANY_REAL",
            Generic::AnyInt => "ANY_INT",
            Generic::AnyBit => "ANY_BIT",
            Generic::AnyString => "ANY_STRING",
            Generic::AnyDate => "ANY_DATE",
        }
    }

    /// Parses a generic type name (`ANY_NUM`, case-insensitive).
    pub fn from_name(name: &str) -> Option<Generic> {
        let g = match name.to_ascii_uppercase().as_str() {
            "ANY" | "ANY_DERIVED" => Generic::Any,
            "ANY_ELEMENTARY" => Generic::AnyElementary,
            "ANY_MAGNITUDE" => Generic::AnyMagnitude,
            "ANY_NUM" => Generic::AnyNum,
            "ANY_REAL" => Generic::AnyReal,
            "ANY_INT" => Generic::AnyInt,
            "ANY_BIT" => Generic::AnyBit,
            "ANY_STRING" => Generic::AnyString,
            "ANY_DATE" => Generic::AnyDate,
            _ => return None,
        };
        Some(g)
    }

    /// Whether `ty` belongs to the class (the error type belongs to every class).
    pub fn admits(self, ty: &Type) -> bool {
        let ty = ty.base();
        if ty.is_error() {
            return true;
        }
        match self {
            Generic::Any => true,
            // A pointer is compared (`p <> 0`, `p = q`) as an address, an interface as what it
            // designates.
            Generic::AnyElementary => ty.is_elementary() || matches!(ty, Type::Pointer(_) | Type::Interface(_)),
            Generic::AnyMagnitude => ty.is_num() || ty.is_duration(),
            Generic::AnyNum => ty.is_num(),
            Generic::AnyReal => ty.is_real(),
            Generic::AnyInt => ty.is_integer(),
            Generic::AnyBit => ty.is_bit(),
            Generic::AnyString => ty.is_string(),
            Generic::AnyDate => ty.is_date(),
        }
    }
}

/// The spellings of the elementary types, longest first so that prefix matching of conversion
/// names (`TIME_OF_DAY_TO_…` before `TIME_TO_…`) finds the right one.
pub(crate) const ELEMENTARY_NAMES: &[&str] = &[
    "DATE_AND_TIME",
    "TIME_OF_DAY",
    "WSTRING",
    "STRING",
    "LWORD",
    "DWORD",
    "ULINT",
    "UDINT",
    "USINT",
    "LREAL",
    "LTIME",
    "SINT",
    "DINT",
    "LINT",
    "UINT",
    "BYTE",
    "WORD",
    "REAL",
    "TIME",
    "DATE",
    "BOOL",
    "INT",
    "TOD",
    "DT",
];

impl Type {
    /// The elementary type with this IEC name (case-insensitive; `TOD`, `DT` accepted).
    pub fn elementary(name: &str) -> Option<Type> {
        let t = match name.to_ascii_uppercase().as_str() {
            "BOOL" => Type::Bool,
            "SINT" => Type::SInt,
            "INT" => Type::Int,
            "DINT" => Type::DInt,
            "LINT" => Type::LInt,
            "USINT" => Type::USInt,
            "UINT" => Type::UInt,
            "UDINT" => Type::UDInt,
            "ULINT" => Type::ULInt,
            "BYTE" => Type::Byte,
            "WORD" => Type::Word,
            "DWORD" => Type::DWord,
            "LWORD" => Type::LWord,
            "REAL" => Type::Real,
            "LREAL" => Type::LReal,
            "TIME" => Type::Time,
            "LTIME" => Type::LTime,
            "DATE" => Type::Date,
            "TIME_OF_DAY" | "TOD" => Type::TimeOfDay,
            "DATE_AND_TIME" | "DT" => Type::DateAndTime,
            "STRING" => Type::String { len: None },
            "WSTRING" => Type::WString { len: None },
            _ => return None,
        };
        Some(t)
    }

    /// The type itself, or the base type of a subrange (subranges behave as their base).
    pub fn base(&self) -> &Type {
        match self {
            Type::Subrange { base, .. } => base,
            t => t,
        }
    }

    /// The error type (absorbs follow-on errors).
    pub fn is_error(&self) -> bool {
        matches!(self, Type::Error)
    }

    /// `BOOL`.
    pub fn is_bool(&self) -> bool {
        matches!(self.base(), Type::Bool)
    }

    /// ANY_INT: the signed and unsigned integers and their subranges.
    pub fn is_integer(&self) -> bool {
        matches!(
            self.base(),
            Type::SInt | Type::Int | Type::DInt | Type::LInt | Type::USInt | Type::UInt | Type::UDInt | Type::ULInt
        )
    }

    /// ANY_BIT: `BOOL`, `BYTE`, `WORD`, `DWORD`, `LWORD`.
    pub fn is_bit(&self) -> bool {
        matches!(self.base(), Type::Bool | Type::Byte | Type::Word | Type::DWord | Type::LWord)
    }

    /// ANY_REAL: `REAL`, `LREAL`.
    pub fn is_real(&self) -> bool {
        matches!(self.base(), Type::Real | Type::LReal)
    }

    /// ANY_NUM: integers and reals.
    pub fn is_num(&self) -> bool {
        self.is_integer() || self.is_real()
    }

    /// `TIME` or `LTIME`.
    pub fn is_duration(&self) -> bool {
        matches!(self.base(), Type::Time | Type::LTime)
    }

    /// ANY_DATE: `DATE`, `TIME_OF_DAY`, `DATE_AND_TIME`.
    pub fn is_date(&self) -> bool {
        matches!(self.base(), Type::Date | Type::TimeOfDay | Type::DateAndTime)
    }

    /// ANY_STRING: `STRING`, `WSTRING`.
    pub fn is_string(&self) -> bool {
        matches!(self.base(), Type::String { .. } | Type::WString { .. })
    }

    /// Enumerated types.
    pub fn is_enum(&self) -> bool {
        matches!(self, Type::Enum { .. })
    }

    /// ANY_ELEMENTARY: every type that is neither an array, a structure, an enumeration nor a
    /// function block.
    pub fn is_elementary(&self) -> bool {
        let b = self.base();
        b.is_num() || b.is_bit() || b.is_duration() || b.is_date() || b.is_string()
    }

    /// Whether the type is signed (integers, reals, durations).
    pub fn is_signed(&self) -> bool {
        matches!(
            self.base(),
            Type::SInt | Type::Int | Type::DInt | Type::LInt | Type::Real | Type::LReal | Type::Time | Type::LTime
        )
    }

    /// The bytes a value of this type takes on a CODESYS target, as `SIZEOF` counts them:
    /// elementary types by their IEC size (TIME, DATE, TOD and DT 4 bytes), `STRING(n)` n + 1,
    /// `WSTRING(n)` 2 (n + 1) (80 characters by default), an enumeration 2 bytes (its base's
    /// if typed), arrays element by element, structures with each member aligned to its own
    /// alignment and the whole to the largest (CODESYS's default packing), pointers, references
    /// and interfaces 8 bytes (a 64-bit target). `None` for an instance of a function block,
    /// whose layout is the compiler's.
    pub fn byte_size(&self) -> Option<u64> {
        Some(match self {
            Type::Bool | Type::SInt | Type::USInt | Type::Byte => 1,
            Type::Int | Type::UInt | Type::Word => 2,
            Type::DInt | Type::UDInt | Type::DWord | Type::Real => 4,
            Type::Time | Type::Date | Type::TimeOfDay | Type::DateAndTime => 4,
            Type::LInt | Type::ULInt | Type::LWord | Type::LReal | Type::LTime => 8,
            Type::String { len } => u64::from(len.unwrap_or(80)) + 1,
            Type::WString { len } => 2 * (u64::from(len.unwrap_or(80)) + 1),
            Type::Enum { base: Some(b), .. } | Type::Subrange { base: b, .. } => b.byte_size()?,
            Type::Enum { base: None, .. } => 2,
            Type::Array { dims, elem } => {
                let n: i64 = dims.iter().map(|(lo, hi)| (hi - lo + 1).max(0)).product();
                (n.max(0) as u64).checked_mul(elem.byte_size()?)?
            }
            Type::Struct { fields, .. } => {
                let mut at: u64 = 0;
                for (_, t) in fields {
                    let a = t.byte_align()?;
                    at = at.div_ceil(a) * a + t.byte_size()?;
                }
                let a = self.byte_align()?;
                at.div_ceil(a) * a
            }
            Type::Pointer(_) | Type::Reference(_) | Type::Interface(_) => 8,
            Type::FunctionBlock(_) | Type::Error => return None,
        })
    }

    /// The alignment of [`Type::byte_size`]: an elementary type's size, a string's 1, an array's
    /// element's, a structure's largest member's.
    fn byte_align(&self) -> Option<u64> {
        Some(match self {
            Type::String { .. } => 1,
            Type::WString { .. } => 2,
            Type::Array { elem, .. } => elem.byte_align()?,
            Type::Struct { fields, .. } => {
                let mut a = 1;
                for (_, t) in fields {
                    a = a.max(t.byte_align()?);
                }
                a
            }
            t => t.byte_size()?.clamp(1, 8),
        })
    }

    /// The type CODESYS gives `SIZEOF`'s value: the smallest unsigned integer type holding it.
    pub fn sizeof_type(size: Option<u64>) -> Type {
        match size {
            Some(n) if n < 256 => Type::USInt,
            Some(n) if n < 65_536 => Type::UInt,
            Some(n) if n < 4_294_967_296 => Type::UDInt,
            Some(_) => Type::ULInt,
            None => Type::UDInt,
        }
    }

    /// The storage width in bits of numeric, bit-string and duration types.
    pub fn bit_width(&self) -> Option<u32> {
        let w = match self.base() {
            Type::Bool => 1,
            Type::SInt | Type::USInt | Type::Byte => 8,
            Type::Int | Type::UInt | Type::Word => 16,
            Type::DInt | Type::UDInt | Type::DWord | Type::Real => 32,
            Type::LInt | Type::ULInt | Type::LWord | Type::LReal | Type::Time | Type::LTime => 64,
            _ => return None,
        };
        Some(w)
    }

    /// The range of values of integer, bit-string and subrange types (`BOOL` is `0..=1`).
    pub fn int_range(&self) -> Option<(i128, i128)> {
        if let Type::Subrange { lo, hi, .. } = self {
            return Some((i128::from(*lo), i128::from(*hi)));
        }
        if !(self.is_integer() || self.is_bit()) {
            return None;
        }
        let width = self.bit_width()?;
        if self.is_signed() {
            let half = 1i128 << (width - 1);
            Some((-half, half - 1))
        } else {
            Some((0, (1i128 << width) - 1))
        }
    }

    /// Whether a value of `self` may be assigned to a `to` variable without an explicit
    /// conversion (IEC 61131-3 3rd ed. table 11 widening: SINT→INT→DINT→LINT, USINT→UINT→…,
    /// unsigned into a wider signed type, integers into a real that holds them exactly,
    /// REAL→LREAL, BYTE→WORD→DWORD→LWORD, TIME→LTIME).
    pub fn widens_to(&self, to: &Type) -> bool {
        use Type::*;
        if self == to {
            return true;
        }
        matches!(
            (self, to),
            (SInt, Int | DInt | LInt | Real | LReal)
                | (Int, DInt | LInt | Real | LReal)
                | (DInt, LInt | LReal)
                | (USInt, UInt | UDInt | ULInt | Int | DInt | LInt | Real | LReal)
                | (UInt, UDInt | ULInt | DInt | LInt | Real | LReal)
                | (UDInt, ULInt | LInt | LReal)
                | (Real, LReal)
                | (Byte, Word | DWord | LWord)
                | (Word, DWord | LWord)
                | (DWord, LWord)
                | (Time, LTime)
                | (String { .. }, String { .. })
                | (WString { .. }, WString { .. })
        )
    }

    /// Whether a value of type `self` can be assigned to a variable of type `to` (equal types,
    /// widening, subranges to and from their base, strings of any length).
    pub fn assignable_to(&self, to: &Type) -> bool {
        if self.is_error() || to.is_error() {
            return true;
        }
        if self == to {
            return true;
        }
        match (self, to) {
            (Type::Array { dims: d1, elem: e1 }, Type::Array { dims: d2, elem: e2 }) => {
                d1 == d2 && (e1 == e2 || (e1.is_string() && e2.is_string() && e1.assignable_to(e2)))
            }
            _ => self.base().widens_to(to.base()),
        }
    }

    /// The smallest type both `a` and `b` widen to, if any (`SINT`,`USINT` → `INT`;
    /// `DINT`,`REAL` → `LREAL`).
    pub fn common(a: &Type, b: &Type) -> Option<Type> {
        if a.is_error() {
            return Some(b.clone());
        }
        if b.is_error() {
            return Some(a.clone());
        }
        if a == b {
            return Some(a.clone());
        }
        let (ab, bb) = (a.base(), b.base());
        if ab == bb {
            return Some(ab.clone());
        }
        if let (Type::String { .. }, Type::String { .. }) = (ab, bb) {
            return Some(Type::String { len: None });
        }
        if let (Type::WString { .. }, Type::WString { .. }) = (ab, bb) {
            return Some(Type::WString { len: None });
        }
        if ab.widens_to(bb) {
            return Some(bb.clone());
        }
        if bb.widens_to(ab) {
            return Some(ab.clone());
        }
        const LADDER: [Type; 8] =
            [Type::Int, Type::DInt, Type::LInt, Type::Real, Type::LReal, Type::Word, Type::DWord, Type::LWord];
        LADDER.iter().find(|c| ab.widens_to(c) && bb.widens_to(c)).cloned()
    }

    /// The element type of an array.
    pub fn element(&self) -> Option<&Type> {
        match self {
            Type::Array { elem, .. } => Some(elem),
            _ => None,
        }
    }

    /// The type of field `name` of a structure (case-insensitive).
    pub fn field(&self, name: &str) -> Option<&Type> {
        match self {
            Type::Struct { fields, .. } => fields.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, t)| t),
            _ => None,
        }
    }

    /// The ordinal of an enumerated value (case-insensitive).
    pub fn enum_value(&self, name: &str) -> Option<i64> {
        match self {
            Type::Enum { values, .. } => values.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, v)| *v),
            _ => None,
        }
    }

    /// The bit-string type of the same width as an integer (`INT` → `WORD`), for BCD
    /// conversions and direct addresses.
    pub fn bits_of_width(width: u32) -> Option<Type> {
        match width {
            1 => Some(Type::Bool),
            8 => Some(Type::Byte),
            16 => Some(Type::Word),
            32 => Some(Type::DWord),
            64 => Some(Type::LWord),
            _ => None,
        }
    }
}

impl fmt::Display for Type {
    /// IEC spelling, as written in declarations: `INT`, `STRING[10]`, `ARRAY [1..10] OF INT`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Type::Bool => "BOOL",
            Type::SInt => "SINT",
            Type::Int => "INT",
            Type::DInt => "DINT",
            Type::LInt => "LINT",
            Type::USInt => "USINT",
            Type::UInt => "UINT",
            Type::UDInt => "UDINT",
            Type::ULInt => "ULINT",
            Type::Byte => "BYTE",
            Type::Word => "WORD",
            Type::DWord => "DWORD",
            Type::LWord => "LWORD",
            Type::Real => "REAL",
            Type::LReal => "LREAL",
            Type::Time => "TIME",
            Type::LTime => "LTIME",
            Type::Date => "DATE",
            Type::TimeOfDay => "TOD",
            Type::DateAndTime => "DT",
            Type::String { len: None } => "STRING",
            Type::WString { len: None } => "WSTRING",
            Type::String { len: Some(n) } => return write!(f, "STRING[{n}]"),
            Type::WString { len: Some(n) } => return write!(f, "WSTRING[{n}]"),
            Type::Array { dims, elem } => {
                f.write_str("ARRAY [")?;
                for (i, (lo, hi)) in dims.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{lo}..{hi}")?;
                }
                return write!(f, "] OF {elem}");
            }
            Type::Pointer(t) => return write!(f, "POINTER TO {t}"),
            Type::Reference(t) => return write!(f, "REFERENCE TO {t}"),
            Type::Struct { name: Some(n), .. } | Type::Enum { name: Some(n), .. } => n,
            Type::Struct { name: None, fields } => {
                f.write_str("STRUCT")?;
                for (n, t) in fields {
                    write!(f, " {n} : {t};")?;
                }
                return f.write_str(" END_STRUCT");
            }
            Type::Enum { name: None, values, .. } => {
                f.write_str("(")?;
                for (i, (n, _)) in values.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    f.write_str(n)?;
                }
                return f.write_str(")");
            }
            Type::Subrange { base, lo, hi } => return write!(f, "{base} ({lo}..{hi})"),
            Type::FunctionBlock(n) | Type::Interface(n) => n,
            Type::Error => "<error>",
        };
        f.write_str(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_uses_iec_spelling() {
        let a = Type::Array { dims: vec![(1, 10)], elem: Box::new(Type::Int) };
        assert_eq!(a.to_string(), "ARRAY [1..10] OF INT");
        assert_eq!(Type::String { len: Some(10) }.to_string(), "STRING[10]");
        let s = Type::Subrange { base: Box::new(Type::Int), lo: 0, hi: 100 };
        assert_eq!(s.to_string(), "INT (0..100)");
    }

    #[test]
    fn widening_follows_iec() {
        assert!(Type::SInt.widens_to(&Type::LInt));
        assert!(Type::USInt.widens_to(&Type::Int));
        assert!(Type::Int.widens_to(&Type::Real));
        assert!(Type::DInt.widens_to(&Type::LReal));
        assert!(!Type::DInt.widens_to(&Type::Real));
        assert!(!Type::Int.widens_to(&Type::SInt));
        assert!(!Type::Bool.widens_to(&Type::Byte));
        assert!(Type::Byte.widens_to(&Type::LWord));
        assert!(!Type::Real.widens_to(&Type::DInt));
        assert_eq!(Type::common(&Type::SInt, &Type::USInt), Some(Type::Int));
        assert_eq!(Type::common(&Type::DInt, &Type::Real), Some(Type::LReal));
        assert_eq!(Type::common(&Type::LInt, &Type::ULInt), None);
    }

    #[test]
    fn ranges() {
        assert_eq!(Type::SInt.int_range(), Some((-128, 127)));
        assert_eq!(Type::ULInt.int_range(), Some((0, u64::MAX as i128)));
        assert_eq!(Type::Word.int_range(), Some((0, 65535)));
        assert!(Generic::AnyNum.admits(&Type::Subrange { base: Box::new(Type::Int), lo: 0, hi: 5 }));
        assert!(!Generic::AnyBit.admits(&Type::Int));
    }
}
