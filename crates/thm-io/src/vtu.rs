//! VTK XML unstructured grids (`.vtu`): particles, triangle meshes, material points, grids.
//!
//! One writer covers every kind: a grid is points, one cell block (vertices, triangles or
//! quads), point data and cell data. Three encodings:
//!
//! - [`Encoding::Raw`]: appended raw binary, the fastest and smallest (1× the data plus an
//!   8-byte header per array). ParaView reads it; it is not well-formed XML.
//! - [`Encoding::Base64`]: appended base64 (4/3 of the data), well-formed XML.
//! - [`Encoding::Ascii`]: inline decimal text with every `f64` written in its shortest exact
//!   form (round trips bit for bit); for tests and small files.
//!
//! Byte order is little-endian, array headers are `UInt64`, coordinates and fields `Float64`,
//! connectivity and offsets `Int64`, cell types `UInt8`. 2D points and vectors are written with
//! a zero third component.

use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

use base64::engine::general_purpose::STANDARD;

use crate::IoError;
use crate::fsutil::write_atomically;

/// How the data arrays are stored in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Inline decimal text.
    Ascii,
    /// Appended data, base64-encoded.
    Base64,
    /// Appended data, raw little-endian bytes.
    Raw,
}

/// Point coordinates, 2D (written with z = 0) or 3D, borrowed or owned.
#[derive(Debug, Clone)]
pub enum Points<'a> {
    /// Points in the x–y plane.
    D2(Cow<'a, [[f64; 2]]>),
    /// Points in space.
    D3(Cow<'a, [[f64; 3]]>),
}

impl Points<'_> {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Points::D2(p) => p.len(),
            Points::D3(p) => p.len(),
        }
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<'a> From<&'a [[f64; 2]]> for Points<'a> {
    fn from(p: &'a [[f64; 2]]) -> Self {
        Points::D2(Cow::Borrowed(p))
    }
}

impl<'a> From<&'a [[f64; 3]]> for Points<'a> {
    fn from(p: &'a [[f64; 3]]) -> Self {
        Points::D3(Cow::Borrowed(p))
    }
}

impl<'a> From<&'a Vec<[f64; 2]>> for Points<'a> {
    fn from(p: &'a Vec<[f64; 2]>) -> Self {
        Points::D2(Cow::Borrowed(p))
    }
}

impl<'a> From<&'a Vec<[f64; 3]>> for Points<'a> {
    fn from(p: &'a Vec<[f64; 3]>) -> Self {
        Points::D3(Cow::Borrowed(p))
    }
}

/// Point indices of cells with `N` points each, `usize` or `u32`, borrowed or owned.
#[derive(Debug, Clone)]
pub enum CellIndices<'a, const N: usize> {
    /// `usize` indices.
    Usize(Cow<'a, [[usize; N]]>),
    /// `u32` indices (compact meshes).
    U32(Cow<'a, [[u32; N]]>),
}

impl<const N: usize> CellIndices<'_, N> {
    fn len(&self) -> usize {
        match self {
            CellIndices::Usize(c) => c.len(),
            CellIndices::U32(c) => c.len(),
        }
    }

    /// The point indices of cell `c` (`c < len`).
    #[inline]
    fn cell(&self, c: usize) -> [usize; N] {
        match self {
            CellIndices::Usize(v) => v[c],
            CellIndices::U32(v) => v[c].map(|i| i as usize),
        }
    }
}

impl<'a, const N: usize> From<&'a [[usize; N]]> for CellIndices<'a, N> {
    fn from(c: &'a [[usize; N]]) -> Self {
        CellIndices::Usize(Cow::Borrowed(c))
    }
}

impl<'a, const N: usize> From<&'a Vec<[usize; N]>> for CellIndices<'a, N> {
    fn from(c: &'a Vec<[usize; N]>) -> Self {
        CellIndices::Usize(Cow::Borrowed(c))
    }
}

impl<'a, const N: usize> From<&'a [[u32; N]]> for CellIndices<'a, N> {
    fn from(c: &'a [[u32; N]]) -> Self {
        CellIndices::U32(Cow::Borrowed(c))
    }
}

impl<'a, const N: usize> From<&'a Vec<[u32; N]>> for CellIndices<'a, N> {
    fn from(c: &'a Vec<[u32; N]>) -> Self {
        CellIndices::U32(Cow::Borrowed(c))
    }
}

/// The cells of a grid: a single block of one cell type.
#[derive(Debug, Clone)]
pub enum Cells<'a> {
    /// One `VTK_VERTEX` per point (particles, material points).
    Vertices,
    /// `VTK_LINE` cells (channels, bonds).
    Lines(CellIndices<'a, 2>),
    /// `VTK_TRIANGLE` cells, counter-clockwise point indices.
    Triangles(CellIndices<'a, 3>),
    /// `VTK_QUAD` cells, counter-clockwise point indices.
    Quads(CellIndices<'a, 4>),
}

impl Cells<'_> {
    fn count(&self, n_points: usize) -> usize {
        match self {
            Cells::Vertices => n_points,
            Cells::Lines(c) => c.len(),
            Cells::Triangles(c) => c.len(),
            Cells::Quads(c) => c.len(),
        }
    }

    fn points_per_cell(&self) -> usize {
        match self {
            Cells::Vertices => 1,
            Cells::Lines(_) => 2,
            Cells::Triangles(_) => 3,
            Cells::Quads(_) => 4,
        }
    }

    /// The VTK cell type code.
    fn vtk_type(&self) -> u8 {
        match self {
            Cells::Vertices => 1,
            Cells::Lines(_) => 3,
            Cells::Triangles(_) => 5,
            Cells::Quads(_) => 9,
        }
    }

    /// Calls `f` with the point indices of cell `c`, in order.
    #[inline]
    fn try_for_each_index<E>(
        &self,
        c: usize,
        mut f: impl FnMut(usize) -> Result<(), E>,
    ) -> Result<(), E> {
        match self {
            Cells::Vertices => f(c),
            Cells::Lines(v) => v.cell(c).into_iter().try_for_each(f),
            Cells::Triangles(v) => v.cell(c).into_iter().try_for_each(f),
            Cells::Quads(v) => v.cell(c).into_iter().try_for_each(f),
        }
    }
}

/// The values of one field: one tuple per point or per cell.
#[derive(Debug, Clone, Copy)]
pub enum FieldValues<'a> {
    /// One number per tuple.
    Scalar(&'a [f64]),
    /// A 2D vector per tuple (written with a zero third component).
    Vector2(&'a [[f64; 2]]),
    /// A 3D vector per tuple.
    Vector3(&'a [[f64; 3]]),
    /// An integer label per tuple (cell type, phase, particle id).
    Int(&'a [i32]),
}

impl FieldValues<'_> {
    fn len(&self) -> usize {
        match self {
            FieldValues::Scalar(v) => v.len(),
            FieldValues::Vector2(v) => v.len(),
            FieldValues::Vector3(v) => v.len(),
            FieldValues::Int(v) => v.len(),
        }
    }
}

/// A named field.
#[derive(Debug, Clone)]
pub struct Field<'a> {
    /// Name shown in ParaView; say the quantity and unit, e.g. `temperature_K`.
    pub name: String,
    /// The values.
    pub values: FieldValues<'a>,
}

/// An unstructured grid ready to be written: borrowed state, no copies of 3D data.
#[derive(Debug, Clone)]
pub struct UnstructuredGrid<'a> {
    points: Points<'a>,
    cells: Cells<'a>,
    point_data: Vec<Field<'a>>,
    cell_data: Vec<Field<'a>>,
}

impl<'a> UnstructuredGrid<'a> {
    /// Particles or material points: one vertex cell per point.
    pub fn particles(points: impl Into<Points<'a>>) -> Self {
        Self::new(points.into(), Cells::Vertices)
    }

    /// Line segments between points (pore-network channels, bonds).
    pub fn lines(points: impl Into<Points<'a>>, lines: impl Into<CellIndices<'a, 2>>) -> Self {
        Self::new(points.into(), Cells::Lines(lines.into()))
    }

    /// A triangle mesh.
    pub fn triangles(
        points: impl Into<Points<'a>>,
        triangles: impl Into<CellIndices<'a, 3>>,
    ) -> Self {
        Self::new(points.into(), Cells::Triangles(triangles.into()))
    }

    /// A quadrilateral mesh.
    pub fn quads(points: impl Into<Points<'a>>, quads: impl Into<CellIndices<'a, 4>>) -> Self {
        Self::new(points.into(), Cells::Quads(quads.into()))
    }

    /// A regular 2D grid of `cells[0] × cells[1]` quads of size `spacing`, lower-left corner at
    /// `origin`. Nodes are numbered with x fastest: node `(i, j)` is `j·(cells[0]+1) + i`;
    /// cell `(i, j)` is `j·cells[0] + i`.
    pub fn regular_grid_2d(
        origin: [f64; 2],
        spacing: [f64; 2],
        cells: [usize; 2],
    ) -> Result<Self, IoError> {
        for &h in &spacing {
            if !(h.is_finite() && h > 0.0) {
                return Err(IoError::BadValue {
                    quantity: "grid spacing",
                    requirement: "finite and > 0",
                    value: h,
                });
            }
        }
        for &o in &origin {
            if !o.is_finite() {
                return Err(IoError::BadValue {
                    quantity: "grid origin",
                    requirement: "finite",
                    value: o,
                });
            }
        }
        let [nx, ny] = cells;
        let nodes_x = nx + 1;
        let mut points = Vec::with_capacity(nodes_x * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                points.push([
                    origin[0] + i as f64 * spacing[0],
                    origin[1] + j as f64 * spacing[1],
                ]);
            }
        }
        let mut quads = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let n = j * nodes_x + i;
                quads.push([n, n + 1, n + 1 + nodes_x, n + nodes_x]);
            }
        }
        Ok(Self::new(
            Points::D2(Cow::Owned(points)),
            Cells::Quads(CellIndices::Usize(Cow::Owned(quads))),
        ))
    }

    /// A grid of the given points and cells.
    pub fn new(points: Points<'a>, cells: Cells<'a>) -> Self {
        Self {
            points,
            cells,
            point_data: Vec::new(),
            cell_data: Vec::new(),
        }
    }

    /// Adds a field with one tuple per point.
    pub fn with_point_field(mut self, name: impl Into<String>, values: FieldValues<'a>) -> Self {
        self.point_data.push(Field {
            name: name.into(),
            values,
        });
        self
    }

    /// Adds a field with one tuple per cell.
    pub fn with_cell_field(mut self, name: impl Into<String>, values: FieldValues<'a>) -> Self {
        self.cell_data.push(Field {
            name: name.into(),
            values,
        });
        self
    }

    /// Number of points.
    pub fn n_points(&self) -> usize {
        self.points.len()
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cells.count(self.points.len())
    }

    /// Checks field lengths, field names and cell indices.
    pub fn validate(&self) -> Result<(), IoError> {
        let n_points = self.n_points();
        let n_cells = self.n_cells();
        for (fields, location, expected) in [
            (&self.point_data, "point", n_points),
            (&self.cell_data, "cell", n_cells),
        ] {
            for (k, f) in fields.iter().enumerate() {
                if f.values.len() != expected {
                    return Err(IoError::FieldLength {
                        field: f.name.clone(),
                        location,
                        len: f.values.len(),
                        expected,
                    });
                }
                if fields[..k].iter().any(|g| g.name == f.name) {
                    return Err(IoError::DuplicateField {
                        field: f.name.clone(),
                        location,
                    });
                }
            }
        }
        for cell in 0..n_cells {
            self.cells.try_for_each_index(cell, |index| {
                if index < n_points {
                    Ok(())
                } else {
                    Err(IoError::CellIndex {
                        cell,
                        index,
                        n_points,
                    })
                }
            })?;
        }
        Ok(())
    }

    /// Validates the grid and writes it to `path` (atomically: a reader sees the old file or
    /// the complete new one).
    pub fn write_vtu(&self, path: &Path, encoding: Encoding) -> Result<(), IoError> {
        self.validate()?;
        write_atomically(path, |w| self.write_to(w, encoding))
    }

    /// Writes the grid to any sink (no validation: call [`Self::validate`] first).
    pub fn write_to(&self, w: &mut impl Write, encoding: Encoding) -> std::io::Result<()> {
        let arrays = self.arrays();
        let format = match encoding {
            Encoding::Ascii => "ascii",
            Encoding::Base64 | Encoding::Raw => "appended",
        };
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
        )?;
        writeln!(w, "  <UnstructuredGrid>")?;
        writeln!(
            w,
            "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            self.n_points(),
            self.n_cells()
        )?;
        let mut offset = 0usize;
        let mut section = None;
        for a in &arrays {
            if section != Some(a.section) {
                if let Some(s) = section {
                    writeln!(w, "      </{}>", s.tag())?;
                }
                writeln!(w, "      <{}>", a.section.tag())?;
                section = Some(a.section);
            }
            write!(
                w,
                "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"{format}\"",
                a.source.vtk_type(),
                xml_escape(&a.name),
                a.source.components()
            )?;
            match encoding {
                Encoding::Ascii => {
                    writeln!(w, ">")?;
                    a.source.write_ascii(self, w)?;
                    writeln!(w, "        </DataArray>")?;
                }
                Encoding::Raw | Encoding::Base64 => {
                    writeln!(w, " offset=\"{offset}\"/>")?;
                    let bytes = 8 + a.source.byte_len(self);
                    offset += match encoding {
                        Encoding::Base64 => bytes.div_ceil(3) * 4,
                        _ => bytes,
                    };
                }
            }
        }
        if let Some(s) = section {
            writeln!(w, "      </{}>", s.tag())?;
        }
        writeln!(w, "    </Piece>")?;
        writeln!(w, "  </UnstructuredGrid>")?;
        if encoding != Encoding::Ascii {
            let name = if encoding == Encoding::Raw {
                "raw"
            } else {
                "base64"
            };
            write!(w, "  <AppendedData encoding=\"{name}\">\n   _")?;
            let mut chunk = Vec::with_capacity(CHUNK + 64);
            for a in &arrays {
                let header = (a.source.byte_len(self) as u64).to_le_bytes();
                if encoding == Encoding::Raw {
                    w.write_all(&header)?;
                    a.source.write_binary(self, &mut chunk, w)?;
                } else {
                    let mut enc = base64::write::EncoderWriter::new(&mut *w, &STANDARD);
                    enc.write_all(&header)?;
                    a.source.write_binary(self, &mut chunk, &mut enc)?;
                    enc.finish()?;
                }
            }
            writeln!(w, "\n  </AppendedData>")?;
        }
        writeln!(w, "</VTKFile>")?;
        Ok(())
    }

    fn arrays(&self) -> Vec<ArrayRef<'a>> {
        let mut v = Vec::new();
        for f in &self.point_data {
            v.push(ArrayRef {
                section: Section::PointData,
                name: f.name.clone(),
                source: Source::Field(f.values),
            });
        }
        for f in &self.cell_data {
            v.push(ArrayRef {
                section: Section::CellData,
                name: f.name.clone(),
                source: Source::Field(f.values),
            });
        }
        v.push(ArrayRef {
            section: Section::Points,
            name: "Points".into(),
            source: Source::Points,
        });
        for (name, source) in [
            ("connectivity", Source::Connectivity),
            ("offsets", Source::Offsets),
            ("types", Source::Types),
        ] {
            v.push(ArrayRef {
                section: Section::Cells,
                name: name.into(),
                source,
            });
        }
        v
    }
}

/// Bytes gathered before each write to the sink.
const CHUNK: usize = 1 << 16;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Section {
    PointData,
    CellData,
    Points,
    Cells,
}

impl Section {
    fn tag(self) -> &'static str {
        match self {
            Section::PointData => "PointData",
            Section::CellData => "CellData",
            Section::Points => "Points",
            Section::Cells => "Cells",
        }
    }
}

struct ArrayRef<'a> {
    section: Section,
    name: String,
    source: Source<'a>,
}

#[derive(Clone, Copy)]
enum Source<'a> {
    Field(FieldValues<'a>),
    Points,
    Connectivity,
    Offsets,
    Types,
}

/// Appends `x` to `chunk` and hands the chunk to `w` when it is full.
#[inline]
fn push_bytes<const N: usize>(
    chunk: &mut Vec<u8>,
    x: [u8; N],
    w: &mut impl Write,
) -> std::io::Result<()> {
    chunk.extend_from_slice(&x);
    if chunk.len() >= CHUNK {
        w.write_all(chunk)?;
        chunk.clear();
    }
    Ok(())
}

impl Source<'_> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Source::Field(FieldValues::Int(_)) => "Int32",
            Source::Field(_) | Source::Points => "Float64",
            Source::Connectivity | Source::Offsets => "Int64",
            Source::Types => "UInt8",
        }
    }

    fn components(&self) -> usize {
        match self {
            Source::Field(FieldValues::Vector2(_) | FieldValues::Vector3(_)) | Source::Points => 3,
            _ => 1,
        }
    }

    fn tuples(&self, g: &UnstructuredGrid<'_>) -> usize {
        match self {
            Source::Field(f) => f.len(),
            Source::Points => g.n_points(),
            Source::Connectivity => g.n_cells() * g.cells.points_per_cell(),
            Source::Offsets | Source::Types => g.n_cells(),
        }
    }

    fn byte_len(&self, g: &UnstructuredGrid<'_>) -> usize {
        let scalar = match self.vtk_type() {
            "Int32" => 4,
            "UInt8" => 1,
            _ => 8,
        };
        self.tuples(g) * self.components() * scalar
    }

    fn write_binary(
        &self,
        g: &UnstructuredGrid<'_>,
        chunk: &mut Vec<u8>,
        w: &mut impl Write,
    ) -> std::io::Result<()> {
        chunk.clear();
        match self {
            Source::Field(FieldValues::Scalar(v)) => {
                for x in *v {
                    push_bytes(chunk, x.to_le_bytes(), w)?;
                }
            }
            Source::Field(FieldValues::Vector2(v)) => write_vec2(v, chunk, w)?,
            Source::Field(FieldValues::Vector3(v)) => write_vec3(v, chunk, w)?,
            Source::Points => match &g.points {
                Points::D2(p) => write_vec2(p, chunk, w)?,
                Points::D3(p) => write_vec3(p, chunk, w)?,
            },
            Source::Field(FieldValues::Int(v)) => {
                for x in *v {
                    push_bytes(chunk, x.to_le_bytes(), w)?;
                }
            }
            Source::Connectivity => {
                for c in 0..g.n_cells() {
                    g.cells.try_for_each_index(c, |i| {
                        push_bytes(chunk, (i as i64).to_le_bytes(), w)
                    })?;
                }
            }
            Source::Offsets => {
                let k = g.cells.points_per_cell() as i64;
                for c in 1..=g.n_cells() as i64 {
                    push_bytes(chunk, (c * k).to_le_bytes(), w)?;
                }
            }
            Source::Types => {
                let t = g.cells.vtk_type();
                for _ in 0..g.n_cells() {
                    push_bytes(chunk, [t], w)?;
                }
            }
        }
        w.write_all(chunk)?;
        chunk.clear();
        Ok(())
    }

    fn write_ascii(&self, g: &UnstructuredGrid<'_>, w: &mut impl Write) -> std::io::Result<()> {
        match self {
            Source::Field(FieldValues::Scalar(v)) => {
                for x in *v {
                    writeln!(w, "{x:?}")?;
                }
            }
            Source::Field(FieldValues::Vector2(v)) => {
                for [x, y] in *v {
                    writeln!(w, "{x:?} {y:?} 0.0")?;
                }
            }
            Source::Field(FieldValues::Vector3(v)) => {
                for [x, y, z] in *v {
                    writeln!(w, "{x:?} {y:?} {z:?}")?;
                }
            }
            Source::Field(FieldValues::Int(v)) => {
                for x in *v {
                    writeln!(w, "{x}")?;
                }
            }
            Source::Points => match &g.points {
                Points::D2(p) => {
                    for [x, y] in p.iter() {
                        writeln!(w, "{x:?} {y:?} 0.0")?;
                    }
                }
                Points::D3(p) => {
                    for [x, y, z] in p.iter() {
                        writeln!(w, "{x:?} {y:?} {z:?}")?;
                    }
                }
            },
            Source::Connectivity => {
                for c in 0..g.n_cells() {
                    let mut sep = "";
                    g.cells.try_for_each_index(c, |i| {
                        let r = write!(w, "{sep}{i}");
                        sep = " ";
                        r
                    })?;
                    writeln!(w)?;
                }
            }
            Source::Offsets => {
                let k = g.cells.points_per_cell();
                for c in 1..=g.n_cells() {
                    writeln!(w, "{}", c * k)?;
                }
            }
            Source::Types => {
                let t = g.cells.vtk_type();
                for _ in 0..g.n_cells() {
                    writeln!(w, "{t}")?;
                }
            }
        }
        Ok(())
    }
}

fn write_vec2(v: &[[f64; 2]], chunk: &mut Vec<u8>, w: &mut impl Write) -> std::io::Result<()> {
    for [x, y] in v {
        push_bytes(chunk, x.to_le_bytes(), w)?;
        push_bytes(chunk, y.to_le_bytes(), w)?;
        push_bytes(chunk, 0f64.to_le_bytes(), w)?;
    }
    Ok(())
}

fn write_vec3(v: &[[f64; 3]], chunk: &mut Vec<u8>, w: &mut impl Write) -> std::io::Result<()> {
    for [x, y, z] in v {
        push_bytes(chunk, x.to_le_bytes(), w)?;
        push_bytes(chunk, y.to_le_bytes(), w)?;
        push_bytes(chunk, z.to_le_bytes(), w)?;
    }
    Ok(())
}

/// Escapes the five XML special characters.
pub(crate) fn xml_escape(s: &str) -> Cow<'_, str> {
    if !s.contains(['&', '<', '>', '"', '\'']) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// Reverses [`xml_escape`].
pub(crate) fn xml_unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}
