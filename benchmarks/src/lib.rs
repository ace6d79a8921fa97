//! Criterion benchmarks of the THM crates live in `benches/`; peer comparisons (YADE,
//! LIGGGHTS, GeoTaichi) in `peers/NAME/`, which are never run in CI.
