//! The checking bodies of the fuzz targets (see `checks`).

pub mod checks;
