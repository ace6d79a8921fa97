//! PNG line plots of measured curves against reference curves, and their CSV.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (Bitstream Vera licence, see
//! `assets/DejaVuSans-LICENSE.txt`), so plotting needs no system fonts.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use thm_verify::{Plot, SeriesRole};

use crate::IoError;
use crate::csv::csv_field;
use crate::fsutil::write_atomically;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Registers the embedded font with plotters once per process.
pub(crate) fn register_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
                .map_err(|_| "embedded font does not load".to_string())
        })
        .clone()
}

/// Size of a rendered plot in pixels.
pub const PLOT_SIZE: (u32, u32) = (960, 640);

const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 90, 181),
    RGBColor(220, 50, 32),
    RGBColor(0, 150, 60),
    RGBColor(150, 60, 180),
    RGBColor(230, 140, 0),
    RGBColor(60, 60, 60),
];

/// The range covered by the finite values of `v`, widened by 5 % (or by 1 when flat).
fn padded_range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    if lo > hi {
        return None;
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.05 * lo.abs().max(1.0)
    };
    Some((lo - pad, hi + pad))
}

/// Renders `plot` to a PNG image in memory.
pub fn render_plot_png(plot: &Plot) -> Result<Vec<u8>, IoError> {
    let err = |message: String| IoError::Plot {
        plot: plot.name.clone(),
        message,
    };
    register_font().map_err(err)?;
    if let Some(s) = plot.series.iter().find(|s| s.x.len() != s.y.len()) {
        return Err(err(format!(
            "series `{}` has {} x values and {} y values",
            s.label,
            s.x.len(),
            s.y.len()
        )));
    }
    let xs = plot.series.iter().flat_map(|s| s.x.iter().copied());
    let ys = plot.series.iter().flat_map(|s| s.y.iter().copied());
    let (Some(xr), Some(yr)) = (padded_range(xs), padded_range(ys)) else {
        return Err(err("no finite point to draw".into()));
    };
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let de = |e: DrawingAreaErrorKind<_>| err(e.to_string());
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&plot.title, ("sans-serif", 26))
            .margin(16)
            .x_label_area_size(56)
            .y_label_area_size(96)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(de)?;
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc(&plot.y_label)
            .axis_desc_style(("sans-serif", 20))
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(de)?;
        for (k, s) in plot.series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let pts: Vec<(f64, f64)> =
                s.x.iter()
                    .zip(&s.y)
                    .map(|(&x, &y)| (x, y))
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect();
            let anno = match s.role {
                SeriesRole::Reference => chart
                    .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                    .map_err(de)?,
                SeriesRole::Measured => chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| Circle::new(p, 4, color.stroke_width(2))),
                    )
                    .map_err(de)?,
            };
            anno.label(s.label.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 18))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(de)?;
        root.present().map_err(de)?;
    }
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Best);
        enc.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
        let mut writer = enc.write_header().map_err(|e| err(e.to_string()))?;
        writer
            .write_image_data(&rgb)
            .map_err(|e| err(e.to_string()))?;
        writer.finish().map_err(|e| err(e.to_string()))?;
    }
    Ok(png_bytes)
}

/// Renders `plot` to a PNG file.
pub fn write_plot_png(plot: &Plot, path: &Path) -> Result<(), IoError> {
    let bytes = render_plot_png(plot)?;
    write_atomically(path, |w| std::io::Write::write_all(w, &bytes))
}

/// Writes the curves of `plot` as CSV in long form: `series,role,<x label>,<y label>`.
pub fn write_plot_csv(plot: &Plot, path: &Path) -> Result<(), IoError> {
    write_atomically(path, |w| {
        use std::io::Write as _;
        writeln!(
            w,
            "series,role,{},{}",
            csv_field(&plot.x_label),
            csv_field(&plot.y_label)
        )?;
        for s in &plot.series {
            let role = match s.role {
                SeriesRole::Measured => "measured",
                SeriesRole::Reference => "reference",
            };
            let label = csv_field(&s.label);
            for (x, y) in s.x.iter().zip(&s.y) {
                writeln!(w, "{label},{role},{x:?},{y:?}")?;
            }
        }
        Ok(())
    })
}
