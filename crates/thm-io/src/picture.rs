//! PNG pictures of filled polygons and line segments in world coordinates (a mesh, a
//! packing), drawn at equal scales on both axes.
//!
//! The caller gives the shapes in metres with their colours; the picture is as wide as asked
//! and as tall as the shapes' bounding box needs (plus a title band), and is written
//! atomically. No physics lives here: which cell gets which colour is the caller's choice.

use std::path::Path;

use plotters::prelude::*;

use crate::IoError;
use crate::fsutil::write_atomically;
use crate::plot::register_font;

/// An 8-bit sRGB colour.
pub type Rgb = [u8; 3];

/// A filled polygon (a triangle, a cell), optionally outlined.
#[derive(Debug, Clone, PartialEq)]
pub struct FilledPolygon {
    /// Corners in world coordinates \[m\], in order (either orientation).
    pub corners: Vec<[f64; 2]>,
    /// Fill colour.
    pub fill: Rgb,
    /// Colour of a one-pixel outline, or `None`.
    pub outline: Option<Rgb>,
}

/// A straight segment drawn over the polygons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// End points in world coordinates \[m\].
    pub ends: [[f64; 2]; 2],
    /// Colour.
    pub colour: Rgb,
}

/// A colour bar drawn under the picture: how a colour reads as a value.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourBar {
    /// What the colours show, with the unit (e.g. `solid temperature [K]`).
    pub label: String,
    /// Values at the left and the right end of the bar.
    pub range: [f64; 2],
    /// Colours from the left to the right end, drawn as equal bands (at least one).
    pub colours: Vec<Rgb>,
}

/// What to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// Title written above the drawing (empty: no title band).
    pub title: String,
    /// Width of the image in pixels (16 to 8192); the height follows from the aspect ratio.
    pub width_px: u32,
    /// Background colour.
    pub background: Rgb,
    /// Polygons, drawn in order (later ones on top).
    pub polygons: Vec<FilledPolygon>,
    /// Segments, drawn after the polygons.
    pub segments: Vec<Segment>,
    /// Colour bars under the drawing, one per row.
    pub colour_bars: Vec<ColourBar>,
    /// Length of a scale bar drawn under the drawing \[m\] (labelled in mm), or `None`.
    pub length_scale: Option<f64>,
}

/// Margin around the drawing \[px\].
const MARGIN_PX: u32 = 8;
/// Height of the title band \[px\].
const TITLE_PX: u32 = 34;
/// Largest image side \[px\].
const MAX_SIDE_PX: u32 = 8192;
/// Height of one colour bar's row (bar and its labels) \[px\].
const COLOUR_BAR_PX: u32 = 46;
/// Height of the bar itself \[px\].
const BAR_PX: i32 = 14;
/// Height of the length scale's row \[px\].
const LENGTH_SCALE_PX: u32 = 30;
/// Font size of the labels under the drawing \[px\].
const LABEL_FONT_PX: u32 = 16;

fn colour(c: Rgb) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Renders `picture` to a PNG image in memory.
pub fn render_picture_png(picture: &Picture) -> Result<Vec<u8>, IoError> {
    let err = |message: String| IoError::Plot {
        plot: picture.title.clone(),
        message,
    };
    if !(16..=MAX_SIDE_PX).contains(&picture.width_px) {
        return Err(IoError::BadValue {
            quantity: "picture width [px]",
            requirement: "between 16 and 8192",
            value: picture.width_px as f64,
        });
    }
    let points = picture
        .polygons
        .iter()
        .flat_map(|p| p.corners.iter())
        .chain(picture.segments.iter().flat_map(|s| s.ends.iter()));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for k in 0..2 {
            if !p[k].is_finite() {
                return Err(IoError::BadValue {
                    quantity: "picture coordinate [m]",
                    requirement: "finite",
                    value: p[k],
                });
            }
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !(lo[0] < hi[0] && lo[1] < hi[1]) {
        return Err(err("nothing with a positive extent to draw".into()));
    }
    let inner_w = picture.width_px.saturating_sub(2 * MARGIN_PX).max(1);
    let scale = inner_w as f64 / (hi[0] - lo[0]);
    let title_px = if picture.title.is_empty() {
        0
    } else {
        TITLE_PX
    };
    let inner_h = ((hi[1] - lo[1]) * scale).ceil() as u32;
    for bar in &picture.colour_bars {
        if bar.colours.is_empty() || !bar.range.iter().all(|v| v.is_finite()) {
            return Err(err(format!(
                "colour bar `{}` needs colours and a finite range",
                bar.label
            )));
        }
    }
    if let Some(l) = picture.length_scale
        && !(l.is_finite() && l > 0.0 && l * scale <= inner_w as f64)
    {
        return Err(IoError::BadValue {
            quantity: "length scale [m]",
            requirement: "positive and at most the drawing's width",
            value: l,
        });
    }
    let legend_px = picture.colour_bars.len() as u32 * COLOUR_BAR_PX
        + picture.length_scale.map_or(0, |_| LENGTH_SCALE_PX);
    let height_px = inner_h + 2 * MARGIN_PX + title_px + legend_px;
    if height_px > MAX_SIDE_PX {
        return Err(IoError::BadValue {
            quantity: "picture height [px]",
            requirement: "at most 8192 (draw narrower)",
            value: height_px as f64,
        });
    }
    // World → pixel: x to the right, y up (image rows go down).
    let top = (MARGIN_PX + title_px) as f64;
    let to_px = |p: &[f64; 2]| -> (i32, i32) {
        (
            (MARGIN_PX as f64 + (p[0] - lo[0]) * scale).round() as i32,
            (top + (hi[1] - p[1]) * scale).round() as i32,
        )
    };
    let (w, h) = (picture.width_px, height_px);
    let mut rgb = vec![255u8; (w as usize) * (h as usize) * 3];
    {
        let de = |e: DrawingAreaErrorKind<_>| err(e.to_string());
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&colour(picture.background)).map_err(de)?;
        if !picture.title.is_empty() {
            register_font().map_err(err)?;
            root.draw(&Text::new(
                picture.title.as_str(),
                (MARGIN_PX as i32, (MARGIN_PX / 2) as i32),
                ("sans-serif", 22).into_font().color(&BLACK),
            ))
            .map_err(de)?;
        }
        for p in &picture.polygons {
            let px: Vec<(i32, i32)> = p.corners.iter().map(to_px).collect();
            root.draw(&Polygon::new(px.clone(), colour(p.fill).filled()))
                .map_err(de)?;
            if let Some(c) = p.outline {
                let mut closed = px;
                if let Some(&first) = closed.first() {
                    closed.push(first);
                }
                root.draw(&PathElement::new(closed, colour(c)))
                    .map_err(de)?;
            }
        }
        for s in &picture.segments {
            root.draw(&PathElement::new(
                vec![to_px(&s.ends[0]), to_px(&s.ends[1])],
                colour(s.colour),
            ))
            .map_err(de)?;
        }
        // The legend: a band under the drawing, as wide as it.
        let left = MARGIN_PX as i32;
        let width = inner_w as i32;
        let mut y = (MARGIN_PX + title_px + inner_h + MARGIN_PX) as i32;
        if legend_px > 0 {
            register_font().map_err(err)?;
            root.draw(&Rectangle::new(
                [(0, y - MARGIN_PX as i32 / 2), (w as i32, h as i32)],
                WHITE.filled(),
            ))
            .map_err(de)?;
        }
        let font = || ("sans-serif", LABEL_FONT_PX).into_font().color(&BLACK);
        for bar in &picture.colour_bars {
            let n = bar.colours.len() as i32;
            for (k, c) in bar.colours.iter().enumerate() {
                let k = k as i32;
                let (x0, x1) = (left + width * k / n, left + width * (k + 1) / n);
                root.draw(&Rectangle::new(
                    [(x0, y), (x1, y + BAR_PX)],
                    colour(*c).filled(),
                ))
                .map_err(de)?;
            }
            root.draw(&Rectangle::new(
                [(left, y), (left + width, y + BAR_PX)],
                BLACK,
            ))
            .map_err(de)?;
            let [lo_v, hi_v] = bar.range;
            let text_y = y + BAR_PX + 2;
            root.draw(&Text::new(format_value(lo_v), (left, text_y), font()))
                .map_err(de)?;
            let hi_text = format_value(hi_v);
            let hi_w = root.estimate_text_size(&hi_text, &font()).map_err(de)?.0 as i32;
            root.draw(&Text::new(hi_text, (left + width - hi_w, text_y), font()))
                .map_err(de)?;
            let label_w = root.estimate_text_size(&bar.label, &font()).map_err(de)?.0 as i32;
            root.draw(&Text::new(
                bar.label.as_str(),
                (
                    left + (width - label_w) / 2,
                    text_y + LABEL_FONT_PX as i32 + 1,
                ),
                font(),
            ))
            .map_err(de)?;
            y += COLOUR_BAR_PX as i32;
        }
        if let Some(l) = picture.length_scale {
            let len = (l * scale).round() as i32;
            let mid = y + 6;
            root.draw(&PathElement::new(
                vec![(left, mid), (left + len, mid)],
                BLACK.stroke_width(3),
            ))
            .map_err(de)?;
            for x in [left, left + len] {
                root.draw(&PathElement::new(vec![(x, mid - 5), (x, mid + 5)], BLACK))
                    .map_err(de)?;
            }
            root.draw(&Text::new(
                format!("{} mm", format_value(l * 1e3)),
                (left + len + 8, mid - LABEL_FONT_PX as i32 / 2),
                font(),
            ))
            .map_err(de)?;
        }
        root.present().map_err(de)?;
    }
    // The rasteriser blends edges; snapping every pixel to the nearest colour the picture
    // names keeps it flat-shaded, so it is stored with a small palette.
    let mut named: Vec<Rgb> = vec![picture.background, [0, 0, 0]];
    named.extend(
        picture
            .polygons
            .iter()
            .flat_map(|p| std::iter::once(p.fill).chain(p.outline)),
    );
    named.extend(picture.segments.iter().map(|s| s.colour));
    named.extend(
        picture
            .colour_bars
            .iter()
            .flat_map(|b| b.colours.iter().copied()),
    );
    named.sort_unstable();
    named.dedup();
    if named.len() <= 256 {
        snap_to_palette(&mut rgb, &named);
    }
    encode_png(&rgb, w, h).map_err(|e| err(e.to_string()))
}

/// A legend value with four significant digits, without trailing zeros.
fn format_value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Replaces every pixel of `rgb` by the nearest colour of `palette` (squared RGB distance).
fn snap_to_palette(rgb: &mut [u8], palette: &[Rgb]) {
    let mut last: Option<(Rgb, Rgb)> = None;
    for px in rgb.chunks_exact_mut(3) {
        let c = [px[0], px[1], px[2]];
        let near = match last {
            Some((from, to)) if from == c => to,
            _ => {
                let d =
                    |p: &Rgb| -> i32 { (0..3).map(|k| (p[k] as i32 - c[k] as i32).pow(2)).sum() };
                let to = palette.iter().copied().min_by_key(d).unwrap_or(c);
                last = Some((c, to));
                to
            }
        };
        px.copy_from_slice(&near);
    }
}

/// PNG of an RGB buffer: indexed colour when at most 256 colours occur (flat-shaded
/// pictures, many times smaller), true colour otherwise.
fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, png::EncodingError> {
    let mut palette: Vec<[u8; 3]> = Vec::new();
    let mut index_of: std::collections::HashMap<[u8; 3], u8> = std::collections::HashMap::new();
    let mut indexed = Vec::with_capacity(rgb.len() / 3);
    for px in rgb.chunks_exact(3) {
        let c = [px[0], px[1], px[2]];
        let i = match index_of.get(&c) {
            Some(&i) => i,
            None if palette.len() < 256 => {
                let i = palette.len() as u8;
                palette.push(c);
                index_of.insert(c, i);
                i
            }
            None => {
                palette.clear();
                break;
            }
        };
        indexed.push(i);
    }
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, w, h);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Best);
        enc.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
        let data: &[u8] = if palette.is_empty() {
            enc.set_color(png::ColorType::Rgb);
            rgb
        } else {
            enc.set_color(png::ColorType::Indexed);
            enc.set_palette(palette.concat());
            &indexed
        };
        let mut writer = enc.write_header()?;
        writer.write_image_data(data)?;
        writer.finish()?;
    }
    Ok(png_bytes)
}

/// Renders `picture` to a PNG file (written to a temporary sibling, then renamed).
pub fn write_picture_png(picture: &Picture, path: &Path) -> Result<(), IoError> {
    let bytes = render_picture_png(picture)?;
    write_atomically(path, |w| std::io::Write::write_all(w, &bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
        dec.set_transformations(png::Transformations::EXPAND);
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// A red square on the left half and a blue one on the right of a 2 × 1 m frame: the
    /// image keeps the aspect ratio and each pixel centre shows the colour of the shape it
    /// lies in.
    #[test]
    fn squares_land_where_they_are() {
        let square = |x0: f64, fill: Rgb| FilledPolygon {
            corners: vec![[x0, 0.0], [x0 + 1.0, 0.0], [x0 + 1.0, 1.0], [x0, 1.0]],
            fill,
            outline: None,
        };
        let pic = Picture {
            title: String::new(),
            width_px: 216,
            background: [255, 255, 255],
            polygons: vec![square(0.0, [255, 0, 0]), square(1.0, [0, 0, 255])],
            segments: vec![],
            colour_bars: vec![],
            length_scale: None,
        };
        let (w, h, rgb) = decode(&render_picture_png(&pic).unwrap());
        assert_eq!(w, 216);
        // 200 px for 2 m: 100 px for the 1 m height, plus the margins.
        assert_eq!(h, 100 + 2 * MARGIN_PX);
        let at = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            [rgb[i], rgb[i + 1], rgb[i + 2]]
        };
        let mid = MARGIN_PX + 50;
        assert_eq!(at(MARGIN_PX + 50, mid), [255, 0, 0]);
        assert_eq!(at(MARGIN_PX + 150, mid), [0, 0, 255]);
        assert_eq!(at(2, 2), [255, 255, 255]);
    }

    /// A colour bar and a length scale go under the drawing: the image grows by their rows,
    /// the bar's bands lie left to right in order, and the scale bar is as long in pixels as
    /// its length at the drawing's scale.
    #[test]
    fn colour_bar_and_length_scale_sit_under_the_drawing() {
        let pic = Picture {
            title: String::new(),
            width_px: 216,
            background: [255, 255, 255],
            polygons: vec![FilledPolygon {
                corners: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]],
                fill: [0, 128, 0],
                outline: None,
            }],
            segments: vec![],
            colour_bars: vec![ColourBar {
                label: "temperature [K]".into(),
                range: [278.16, 368.16],
                colours: vec![[255, 0, 0], [0, 0, 255]],
            }],
            length_scale: Some(0.5),
        };
        let (w, h, rgb) = decode(&render_picture_png(&pic).unwrap());
        assert_eq!(h, 100 + 2 * MARGIN_PX + COLOUR_BAR_PX + LENGTH_SCALE_PX);
        let at = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            [rgb[i], rgb[i + 1], rgb[i + 2]]
        };
        let bar_y = 100 + 2 * MARGIN_PX + BAR_PX as u32 / 2;
        assert_eq!(at(MARGIN_PX + 50, bar_y), [255, 0, 0]);
        assert_eq!(at(MARGIN_PX + 150, bar_y), [0, 0, 255]);
        // 0.5 m at 100 px/m: black from the left end to 50 px, white beyond the label's gap.
        let scale_y = 100 + 2 * MARGIN_PX + COLOUR_BAR_PX + 6;
        assert_eq!(at(MARGIN_PX + 25, scale_y), [0, 0, 0]);
        assert_eq!(at(MARGIN_PX + 49, scale_y), [0, 0, 0]);
        assert_eq!(at(MARGIN_PX + 54, scale_y + 10), [255, 255, 255]);
        let mut bad = pic.clone();
        bad.colour_bars[0].colours.clear();
        assert!(matches!(
            render_picture_png(&bad),
            Err(IoError::Plot { .. })
        ));
        let mut bad = pic;
        bad.length_scale = Some(3.0);
        assert!(matches!(
            render_picture_png(&bad),
            Err(IoError::BadValue { .. })
        ));
        assert_eq!(format_value(278.16), "278.2");
        assert_eq!(format_value(0.0116), "0.0116");
        assert_eq!(format_value(10.0), "10");
    }

    /// More than 256 colours fall back to true colour and still decode to the same pixels.
    #[test]
    fn many_colours_round_trip() {
        let (w, h) = (40u32, 20u32);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| [(i % 256) as u8, (i / 256) as u8, 7])
            .collect();
        let (dw, dh, back) = decode(&encode_png(&rgb, w, h).unwrap());
        assert_eq!((dw, dh), (w, h));
        assert_eq!(back, rgb);
        let flat: Vec<u8> = (0..w * h)
            .flat_map(|i| [(i % 3) as u8 * 100, 0, 0])
            .collect();
        let (_, _, back) = decode(&encode_png(&flat, w, h).unwrap());
        assert_eq!(back, flat);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let mut pic = Picture {
            title: "t".into(),
            width_px: 100,
            background: [0, 0, 0],
            polygons: vec![FilledPolygon {
                corners: vec![[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]],
                fill: [1, 2, 3],
                outline: None,
            }],
            segments: vec![],
            colour_bars: vec![],
            length_scale: None,
        };
        assert!(matches!(
            render_picture_png(&pic),
            Err(IoError::BadValue { .. })
        ));
        pic.polygons[0].corners[1][1] = 0.0;
        pic.width_px = 4;
        assert!(matches!(
            render_picture_png(&pic),
            Err(IoError::BadValue { .. })
        ));
        pic.width_px = 100;
        pic.polygons.clear();
        assert!(matches!(
            render_picture_png(&pic),
            Err(IoError::Plot { .. })
        ));
    }

    #[test]
    fn written_file_decodes() {
        let dir = std::env::temp_dir().join(format!("thm-io-picture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tri.png");
        let pic = Picture {
            title: "a triangle".into(),
            width_px: 64,
            background: [255, 255, 255],
            polygons: vec![FilledPolygon {
                corners: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                fill: [0, 128, 0],
                outline: Some([0, 0, 0]),
            }],
            segments: vec![Segment {
                ends: [[0.0, 0.0], [1.0, 1.0]],
                colour: [255, 0, 0],
            }],
            colour_bars: vec![],
            length_scale: None,
        };
        write_picture_png(&pic, &path).unwrap();
        let (w, h, _) = decode(&std::fs::read(&path).unwrap());
        assert_eq!((w, h), (64, 48 + 2 * MARGIN_PX + TITLE_PX));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
