//! The validated diagram (feature `std`): [`Diagram`] = [`DiagramData`] that passed every
//! check, with its checksum and LUT id; constructors, accessors and file I/O.

use std::fs;
use std::path::Path;

use crate::data::{Axes, DiagramData, GridPoint, Header};
use crate::file::{self, decode_unvalidated, err, write_atomically, FileProblem, LoadError};
use crate::validate::{check_cell, check_cells, check_thresholds, limits};
use crate::{Cell, DiagramView, Lookup, Problem, Query, AXIS_COUNT};

/// A validated characteristic diagram with its checksum and LUT id.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagram {
    data: DiagramData,
    checksum: u32,
}

impl Diagram {
    /// Validate `data` and compute its checksum.
    pub fn new(data: DiagramData) -> Result<Self, Problem> {
        validate_data(&data)?;
        let checksum = file::checksum_of(&data);
        Ok(Diagram { data, checksum })
    }

    /// Build from row-major cells (index = [`Axes::cell_index`]). Shards
    /// computed as contiguous index ranges are simply concatenated in order.
    pub fn from_cells(header: Header, axes: Axes, cells: Vec<Cell>) -> Result<Self, Problem> {
        Self::new(DiagramData {
            header,
            axes,
            cells,
        })
    }

    /// Build from `(row-major index, cell)` pairs in any order (e.g. shards
    /// finishing out of order). Every index must appear exactly once.
    pub fn from_indexed_cells(
        header: Header,
        axes: Axes,
        cells: impl IntoIterator<Item = (usize, Cell)>,
    ) -> Result<Self, Problem> {
        axes.validate()?;
        let count = axes.cell_count();
        let mut slots: Vec<Option<Cell>> = vec![None; count];
        for (index, cell) in cells {
            match slots.get_mut(index) {
                Some(slot @ None) => *slot = Some(cell),
                _ => return Err(Problem::CellIndexInvalid { index, count }),
            }
        }
        let mut out = Vec::with_capacity(count);
        for (index, slot) in slots.into_iter().enumerate() {
            match slot {
                Some(c) => out.push(c),
                None => {
                    return Err(Problem::CellMissing {
                        index,
                        coords: axes.cell_coords(index).unwrap_or([0; AXIS_COUNT]),
                    })
                }
            }
        }
        Self::from_cells(header, axes, out)
    }

    /// Build by evaluating `f` at every grid point, in row-major order.
    pub fn from_fn(
        header: Header,
        axes: Axes,
        mut f: impl FnMut(GridPoint) -> Cell,
    ) -> Result<Self, Problem> {
        axes.validate()?;
        let count = axes.cell_count();
        let mut cells = Vec::with_capacity(count);
        for index in 0..count {
            let p = axes.point(index).ok_or(Problem::CellCount {
                expected: count,
                found: index,
            })?;
            let cell = f(p);
            check_cell(index, p.coords, &cell)?;
            cells.push(cell);
        }
        Self::from_cells(header, axes, cells)
    }

    /// Header.
    pub fn header(&self) -> &Header {
        &self.data.header
    }

    /// Axes.
    pub fn axes(&self) -> &Axes {
        &self.data.axes
    }

    /// Row-major cells.
    pub fn cells(&self) -> &[Cell] {
        &self.data.cells
    }

    /// All data (e.g. to inspect or to derive a modified table).
    pub fn data(&self) -> &DiagramData {
        &self.data
    }

    /// Give up validation and take the plain data back.
    pub fn into_data(self) -> DiagramData {
        self.data
    }

    /// CRC-32C of the binary encoding (see the README's file layout).
    pub fn checksum(&self) -> u32 {
        self.checksum
    }

    /// LUT id the ECU reports in its CAN heartbeat: the two 16-bit halves of
    /// the checksum XOR-ed, so any content change changes it with high probability.
    pub fn lut_id(&self) -> u16 {
        lut_id_of(self.checksum)
    }

    /// Borrowed, validated `no_std` view for allocation-free lookups.
    pub fn view(&self) -> DiagramView<'_> {
        let a = &self.data.axes;
        // `self` was validated with the same rules in `Diagram::new`.
        DiagramView::from_validated(
            a.as_slices(),
            &self.data.cells,
            a.nan_fallback,
            self.data.header.airbag_thresholds,
        )
    }

    /// Convenience: one lookup through a fresh view (cheap: no
    /// re-validation, no allocation).
    pub fn lookup(&self, q: &Query) -> Lookup {
        self.view().lookup(q)
    }
}

/// LUT id from a checksum (see [`Diagram::lut_id`]).
pub fn lut_id_of(checksum: u32) -> u16 {
    ((checksum >> 16) ^ (checksum & 0xFFFF)) as u16
}

pub(crate) fn validate_data(d: &DiagramData) -> Result<(), Problem> {
    let ego = &d.header.ego;
    let (lo, hi) = limits::EGO_MASS_KG;
    if !(ego.mass_kg >= lo && ego.mass_kg <= hi && (1..=6).contains(&ego.class)) {
        return Err(Problem::EgoVehicle {
            mass_kg: ego.mass_kg,
            class: ego.class,
        });
    }
    check_thresholds(&d.header.airbag_thresholds)?;
    d.axes.validate()?;
    check_cells(d.axes.lens(), &d.cells)
}

/// File I/O: the binary format and the JSON export of `file.rs`, validated on the way in.
impl Diagram {
    /// Encode into the binary file format.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.data().to_bytes_unvalidated()
    }

    /// Decode and validate a binary file's bytes. `file` names the file in errors.
    pub fn from_bytes(file: &str, bytes: &[u8]) -> Result<Self, LoadError> {
        let data = decode_unvalidated(bytes).map_err(|p| err(file, p))?;
        Diagram::new(data).map_err(|p| err(file, p))
    }

    /// Load and validate a binary file (allocates; start-up only).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let bytes = fs::read(path).map_err(|e| err(&name, e))?;
        Self::from_bytes(&name, &bytes)
    }

    /// Load a binary or JSON file, told apart by the magic number (JSON
    /// starts with `{` after optional whitespace).
    pub fn load_any(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let bytes = fs::read(path).map_err(|e| err(&name, e))?;
        let first = bytes.iter().copied().find(|b| !b.is_ascii_whitespace());
        if first == Some(b'{') {
            let text = std::str::from_utf8(&bytes)
                .map_err(|e| err(&name, FileProblem::Json(e.to_string())))?;
            Self::from_json_str(&name, text)
        } else {
            Self::from_bytes(&name, &bytes)
        }
    }

    /// Write the binary file atomically (temporary file + rename), so a
    /// crashed build never leaves a half-written table behind.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), LoadError> {
        write_atomically(path.as_ref(), &self.to_bytes())
    }

    /// JSON export (pretty-printed). Carries the binary encoding's CRC-32C
    /// and the LUT id so that an import reproduces the identical table.
    pub fn to_json_string(&self) -> String {
        file::json_string(self.data(), self.checksum(), self.lut_id())
    }

    /// JSON import with the same validation as the binary loader; if the
    /// JSON carries `crc32c` / `lut_id` they must match the content.
    pub fn from_json_str(file: &str, text: &str) -> Result<Self, LoadError> {
        let (data, crc32c, lut_id) = file::decode_json(text).map_err(|p| err(file, p))?;
        let d = Diagram::new(data).map_err(|p| err(file, p))?;
        if let Some(stored) = crc32c {
            if stored != d.checksum() {
                return Err(err(
                    file,
                    FileProblem::ChecksumMismatch {
                        stored,
                        computed: d.checksum(),
                    },
                ));
            }
        }
        if let Some(stored) = lut_id {
            if stored != d.lut_id() {
                return Err(err(
                    file,
                    FileProblem::LutIdMismatch {
                        stored,
                        computed: d.lut_id(),
                    },
                ));
            }
        }
        Ok(d)
    }

    /// Load a JSON export.
    pub fn load_json(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = fs::read_to_string(path).map_err(|e| err(&name, e))?;
        Self::from_json_str(&name, &text)
    }

    /// Write the JSON export atomically.
    pub fn save_json(&self, path: impl AsRef<Path>) -> Result<(), LoadError> {
        let mut text = self.to_json_string();
        text.push('\n');
        write_atomically(path.as_ref(), text.as_bytes())
    }
}
