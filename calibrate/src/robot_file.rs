//! Writing the calibrated robot file: the input text with only the fitted values changed.
//!
//! The TOML is edited in place (`toml_edit`), so comments, order and formatting survive. Keys
//! the input lacks (`beta`, `[base]`, `[tool] xyz`) are added where a fitted value needs them;
//! a workspace carried into a new world frame replaces the old one.
//! A comment block at the top, between [`BEGIN`] and [`END`], records the calibration; it
//! replaces the block of an earlier calibration.

use armgate_core::config::WorkspaceConfig;
use toml_edit::{Array, DocumentMut, Item, TableLike, Value};

use crate::model::{Geometry, Param};

/// First line of the calibration comment block.
pub const BEGIN: &str = "# >>> armgate-calibrate";
/// Last line of the calibration comment block.
pub const END: &str = "# <<< armgate-calibrate";
/// Written values are rounded to this many decimals (nm, nrad): far below any metrology, short
/// to read.
const DECIMALS: usize = 9;

/// Why the robot file could not be edited.
#[derive(Debug)]
pub struct EditError(toml_edit::TomlError);

impl std::fmt::Display for EditError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "robot file: {}", self.0.to_string().trim_end())
    }
}

impl std::error::Error for EditError {}

/// `original` with the `fitted` parameters set to their values in `geometry`, the `[workspace]`
/// replaced by `workspace` if given, and `comment` (lines without `#`) as the calibration block
/// at the top.
pub fn edit(
    original: &str,
    geometry: &Geometry,
    fitted: &[Param],
    workspace: Option<&WorkspaceConfig>,
    comment: &str,
) -> Result<String, EditError> {
    let mut doc: DocumentMut = without_block(original).parse().map_err(EditError)?;
    if let Some(w) = workspace {
        let row = |b: &[f64; 6]| Value::Array(b.iter().map(|v| rounded(*v)).collect::<Array>());
        let boxes = Value::Array(w.boxes.iter().map(row).collect::<Array>());
        set(table(&mut doc, "workspace"), "bounds", row(&w.bounds));
        if !w.boxes.is_empty() {
            set(table(&mut doc, "workspace"), "boxes", boxes);
        }
    }
    for &p in fitted {
        let number = |p: Param| Value::from(rounded(geometry.get(p)));
        let triple = |make: fn(usize) -> Param| {
            Value::Array((0..3).map(|k| number(make(k))).collect::<Array>())
        };
        match p {
            Param::BaseXyz(_) => set(table(&mut doc, "base"), "xyz", triple(Param::BaseXyz)),
            Param::BaseRpy(_) => set(table(&mut doc, "base"), "rpy", triple(Param::BaseRpy)),
            Param::ToolXyz(_) => set(table(&mut doc, "tool"), "xyz", triple(Param::ToolXyz)),
            Param::Theta(i) => set_joint(&mut doc, i, "theta", number(p)),
            Param::D(i) => set_joint(&mut doc, i, "d", number(p)),
            Param::A(i) => set_joint(&mut doc, i, "a", number(p)),
            Param::Alpha(i) => set_joint(&mut doc, i, "alpha", number(p)),
            Param::Beta(i) => set_joint(&mut doc, i, "beta", number(p)),
            // Not the robot's: written to its own file (`instrument`).
            Param::Instrument(_) => {}
        }
    }
    let mut out = String::from(BEGIN);
    out.push('\n');
    for line in comment.lines() {
        out.push_str(if line.is_empty() { "#" } else { "# " });
        out.push_str(line);
        out.push('\n');
    }
    out.push_str(END);
    out.push('\n');
    out.push_str(&doc.to_string());
    Ok(out)
}

/// `v` rounded to [`DECIMALS`] decimals (its shortest representation is then short too).
fn rounded(v: f64) -> f64 {
    format!("{v:.DECIMALS$}").parse().unwrap_or(v)
}

/// The text without an earlier calibration block.
fn without_block(text: &str) -> String {
    match (text.find(BEGIN), text.find(END)) {
        (Some(begin), Some(end)) if begin < end => {
            let after = text.get(end + END.len()..).unwrap_or("");
            let before = text.get(..begin).unwrap_or("");
            format!("{before}{}", after.strip_prefix('\n').unwrap_or(after))
        }
        _ => text.to_string(),
    }
}

/// The top-level table `name`, created if absent.
fn table<'a>(doc: &'a mut DocumentMut, name: &str) -> Option<&'a mut dyn TableLike> {
    doc.entry(name)
        .or_insert_with(toml_edit::table)
        .as_table_like_mut()
}

/// Sets `key` of joint `index`.
fn set_joint(doc: &mut DocumentMut, index: usize, key: &str, value: Value) {
    let joint = doc
        .get_mut("joints")
        .and_then(Item::as_array_of_tables_mut)
        .and_then(|joints| joints.get_mut(index))
        .map(|t| t as &mut dyn TableLike);
    set(joint, key, value);
}

/// Replaces the value of `key`, keeping its surrounding whitespace and comment, or adds it.
fn set(table: Option<&mut dyn TableLike>, key: &str, value: Value) {
    let Some(table) = table else { return };
    match table.get_mut(key).and_then(Item::as_value_mut) {
        Some(old) => {
            let decor = old.decor().clone();
            *old = value;
            *old.decor_mut() = decor;
        }
        None => {
            table.insert(key, Item::Value(value));
        }
    }
}
