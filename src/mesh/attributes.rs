//! Per-vertex and per-face data carried alongside the face-vertex list: named scalar properties
//! (PLY extras such as colours, confidence, quality), OBJ texture coordinates and normals with
//! their per-corner indices. Readers fill these in and writers put them back, so a file read,
//! written and read again is identical. Operations that change connectivity drop them.

/// Storage type of a property, kept so PLY files are written back with the types they had.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    /// Size in bytes.
    pub fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// Parse a PLY type name (`char`, `uchar`, `int8`, `float32`, …).
    pub fn from_ply(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    /// The PLY type name written back.
    pub fn ply_name(self) -> &'static str {
        match self {
            ScalarType::I8 => "char",
            ScalarType::U8 => "uchar",
            ScalarType::I16 => "short",
            ScalarType::U16 => "ushort",
            ScalarType::I32 => "int",
            ScalarType::U32 => "uint",
            ScalarType::F32 => "float",
            ScalarType::F64 => "double",
        }
    }
}

/// A named scalar property with one value per element (vertex or face).
#[derive(Clone, Debug, PartialEq)]
pub struct Property {
    pub name: String,
    pub ty: ScalarType,
    pub values: Vec<f64>,
}

/// Everything a file carried besides positions and faces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attributes {
    /// Scalar type of the positions in the source file (PLY `float` or `double`).
    pub position_type: Option<ScalarType>,
    /// Scalar type of the face index lists (PLY `list uchar int`: count type, index type).
    pub face_list_types: Option<(ScalarType, ScalarType)>,
    /// Name of the face index property (`vertex_indices` or `vertex_index`).
    pub face_list_name: Option<String>,
    /// Extra per-vertex properties in file order (PLY `nx`, `red`, …).
    pub vertex: Vec<Property>,
    /// Extra per-face properties in file order.
    pub face: Vec<Property>,
    /// OBJ `vt` lines (unused components are 0).
    pub texcoords: Vec<[f64; 3]>,
    /// Number of components the `vt` lines had (2 or 3; 0 when there were none).
    pub texcoord_dim: usize,
    /// OBJ `vn` lines.
    pub normals: Vec<[f64; 3]>,
    /// Per corner index into `texcoords` (empty when the faces had none).
    pub corner_texcoord: Vec<u32>,
    /// Per corner index into `normals` (empty when the faces had none).
    pub corner_normal: Vec<u32>,
    /// Per-vertex normals computed by `mra mesh normals` (written as PLY nx/ny/nz, OBJ vn).
    pub vertex_normals: Option<Vec<[f64; 3]>>,
}

impl Attributes {
    pub fn is_empty(&self) -> bool {
        *self == Attributes::default()
    }
}
