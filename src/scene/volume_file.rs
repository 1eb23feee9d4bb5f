//! A heterogeneous medium's grid from a `.vol` file, for both loaders: read, parsed by the one
//! `.vol` reader (`crate::volume::parse_vol`) and checked for the quantity it gives (sigma_t
//! finite and >= 0, albedo in [0, 1]), every error naming the file.

use crate::medium::VolumeData;
use crate::medium::heterogeneous::check_quantity;
use crate::volume::{VolGrid, VolShape, parse_vol};
use std::path::Path;
use std::sync::Arc;

/// The grid of `path` for quantity `quantity` (`sigma_t` or `albedo`).
pub fn load_medium_grid(path: &Path, quantity: &str) -> Result<Arc<VolGrid>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read grid volume `{}`: {e}", path.display()))?;
    let named = |e: String| format!("grid volume `{}`: {e}", path.display());
    let grid = Arc::new(parse_vol(&bytes, VolShape::MEDIUM).map_err(|e| named(e.to_string()))?);
    check_quantity(quantity, &VolumeData::Grid(grid.clone())).map_err(named)?;
    Ok(grid)
}
