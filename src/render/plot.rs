//! Line plots of numbers over time, drawn with `plotters`' bitmap backend (axes, grid and lines)
//! and labelled with the renderer's built-in pixel font ([`draw_text`]): no system font
//! library is needed (`plotters` is built without its `ttf` feature).
//!
//! ```no_run
//! use rapier_touch::render::plot::LinePlot;
//! use rapier_touch::render::Color;
//!
//! let mut plot = LinePlot::new("A SINE", "T S", "Y M");
//! let points: Vec<(f64, f64)> = (0..100).map(|i| (i as f64 * 0.1, (i as f64 * 0.1).sin())).collect();
//! plot.line("SIN(T)", Color::from_rgba8(30, 90, 200, 255), points);
//! let path = std::env::temp_dir().join("sine.png");
//! plot.save_png(800, 400, path).unwrap();
//! ```

use super::{draw, draw_text, text_size, Color, Pixmap, RenderError};
use plotters::coord::ranged1d::{KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use tiny_skia::{PixmapPaint, Transform};

/// One line of a [`LinePlot`].
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Written in the legend.
    pub label: String,
    /// The points `(x, y)`, in order. Non-finite points break the line; points outside the
    /// plot's ranges are clamped onto its border.
    pub points: Vec<(f64, f64)>,
    /// The line's colour (opaque).
    pub color: Color,
    /// Line width in pixels.
    pub width: u32,
    /// Drawn dashed.
    pub dashed: bool,
}

/// A line plot: a title, axis labels, lines with a legend at the right and optional notes
/// under the legend. Text is written with the built-in font (upper case, see
/// [`draw_text`]).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LinePlot {
    /// Written above the plot (`\n` starts a line).
    pub title: String,
    /// Written under the x axis.
    pub x_label: String,
    /// Written above the y axis.
    pub y_label: String,
    /// The x range; `None`: the data's.
    pub x_range: Option<(f64, f64)>,
    /// The y range; `None`: the data's, from 0 on a linear axis when the data are positive.
    pub y_range: Option<(f64, f64)>,
    /// A logarithmic y axis (values at or below 0 are clamped to the range's bottom).
    pub log_y: bool,
    /// The lines, drawn in order.
    pub series: Vec<Series>,
    /// Lines of text written under the legend.
    pub notes: Vec<String>,
}

const SCALE: f32 = 2.0;
const DARK: (u8, u8, u8) = (30, 30, 30);

fn dark() -> Color {
    Color::from_rgba8(DARK.0, DARK.1, DARK.2, 255)
}

fn rgb(c: Color) -> RGBColor {
    let c = c.to_color_u8();
    RGBColor(c.red(), c.green(), c.blue())
}

/// A tick label: as few decimals as the spacing of the ticks needs.
fn tick_label(v: f64, step: f64, log: bool) -> String {
    let v = if v.abs() < 1e-12 * step.abs().max(1e-300) {
        0.0
    } else {
        v
    };
    // Log ticks are powers of ten up to rounding: snap them.
    let v = if log && v > 0.0 {
        let p = 10f64.powf(v.log10().round());
        if (v / p - 1.0).abs() < 1e-6 {
            p
        } else {
            v
        }
    } else {
        v
    };
    let step = if log { v.abs() } else { step.abs() };
    if step > 0.0 && (step < 1e-4 || v.abs() >= 1e6) {
        return format!("{v:.0E}");
    }
    let decimals = if step > 0.0 {
        (-step.log10().floor()).max(0.0) as usize
    } else {
        0
    };
    format!("{v:.decimals$}")
}

fn plot_error(e: impl std::fmt::Display) -> RenderError {
    RenderError::Png(format!("plot: {e}"))
}

impl LinePlot {
    /// An empty plot with a title and axis labels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Default::default()
        }
    }

    /// Adds a solid line 2 pixels wide and returns it (to make it dashed or wider).
    pub fn line(
        &mut self,
        label: impl Into<String>,
        color: Color,
        points: Vec<(f64, f64)>,
    ) -> &mut Series {
        self.series.push(Series {
            label: label.into(),
            points,
            color,
            width: 2,
            dashed: false,
        });
        self.series.last_mut().expect("just pushed")
    }

    /// The x and y ranges the plot shows.
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let finite = || {
            self.series
                .iter()
                .flat_map(|s| &s.points)
                .filter(|p| p.0.is_finite() && p.1.is_finite())
        };
        let fold = |f: &dyn Fn(&(f64, f64)) -> Option<f64>| {
            finite()
                .filter_map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        };
        let sane = |(lo, hi): (f64, f64), default: (f64, f64)| {
            if lo.is_finite() && hi.is_finite() && hi > lo {
                (lo, hi)
            } else if lo.is_finite() && hi.is_finite() {
                (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
            } else {
                default
            }
        };
        let x = self
            .x_range
            .unwrap_or_else(|| sane(fold(&|p| Some(p.0)), (0.0, 1.0)));
        let x = sane(x, (0.0, 1.0));
        let y = match (self.y_range, self.log_y) {
            (Some(r), _) => r,
            (None, true) => {
                let (lo, hi) = fold(&|p| (p.1 > 0.0).then_some(p.1));
                (lo * 0.5, hi * 2.0)
            }
            (None, false) => {
                let (lo, hi) = fold(&|p| Some(p.1));
                let pad = 0.05 * (hi - lo).max(hi.abs() * 1e-3);
                (
                    if lo >= 0.0 { 0.0 } else { lo - pad },
                    if hi <= 0.0 { 0.0 } else { hi + pad },
                )
            }
        };
        let y = if self.log_y {
            let y = (y.0.max(1e-300), y.1.max(1e-300));
            if y.1 > y.0 {
                y
            } else {
                (1e-3, 1.0)
            }
        } else {
            sane(y, (0.0, 1.0))
        };
        (x, y)
    }

    /// Paints the plot into a new `width × height` picture.
    pub fn render(&self, width: u32, height: u32) -> Result<Pixmap, RenderError> {
        if width < 200 || height < 150 {
            return Err(RenderError::InvalidSize(width, height));
        }
        let mut pm = Pixmap::new(width, height).ok_or(RenderError::InvalidSize(width, height))?;
        let (xr, yr) = self.ranges();
        if self.log_y {
            let coord = (yr.0..yr.1).log_scale();
            let y: LogCoord<f64> = coord.into();
            self.paint(&mut pm, xr, y)?;
        } else {
            let y: RangedCoordf64 = (yr.0..yr.1).into();
            self.paint(&mut pm, xr, y)?;
        }
        Ok(pm)
    }

    /// [`LinePlot::render`], then writes the picture as a PNG file.
    pub fn save_png(
        &self,
        width: u32,
        height: u32,
        path: impl AsRef<std::path::Path>,
    ) -> Result<(), RenderError> {
        let pm = self.render(width, height)?;
        pm.save_png(path)
            .map_err(|e| RenderError::Png(e.to_string()))
    }

    fn paint<Y>(&self, pm: &mut Pixmap, xr: (f64, f64), y: Y) -> Result<(), RenderError>
    where
        Y: Ranged<ValueType = f64>,
    {
        let (w, h) = (pm.width(), pm.height());
        let (y0, y1) = (y.range().start, y.range().end);
        let x: RangedCoordf64 = (xr.0..xr.1).into();
        // Ticks and their labels.
        let x_ticks = x.key_points(KeyPointHint::max_num_points(&((w / 110) as usize).max(2)));
        let y_ticks = y.key_points(KeyPointHint::max_num_points(&((h / 60) as usize).max(2)));
        let step = |t: &[f64]| match t {
            [a, b, ..] => b - a,
            _ => 1.0,
        };
        let x_labels: Vec<String> = x_ticks
            .iter()
            .map(|v| tick_label(*v, step(&x_ticks), false))
            .collect();
        let y_labels: Vec<String> = y_ticks
            .iter()
            .map(|v| tick_label(*v, step(&y_ticks), self.log_y))
            .collect();
        // Margins around the plotting area (pixels).
        let line_h = 6.0 * SCALE;
        let title_lines = self.title.lines().count() as f32;
        let top = 14.0 + title_lines * line_h + 8.0 + line_h + 8.0;
        let y_label_w = y_labels
            .iter()
            .map(|l| text_size(l, SCALE).0)
            .fold(0.0, f32::max);
        let left = (y_label_w + 20.0).max(40.0);
        let legend_w = self
            .series
            .iter()
            .map(|s| text_size(&s.label, SCALE).0 + 44.0)
            .chain(self.notes.iter().map(|n| text_size(n, SCALE).0 + 8.0))
            .fold(0.0, f32::max);
        let right = legend_w + 24.0;
        let bottom = 8.0 + line_h + 10.0 + line_h + 12.0;
        if left + right + 60.0 > w as f32 || top + bottom + 60.0 > h as f32 {
            return Err(RenderError::InvalidSize(w, h));
        }

        let mut buf = vec![255u8; (w * h * 3) as usize];
        let pixel_coords = {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            root.fill(&WHITE).map_err(plot_error)?;
            let mut chart = ChartBuilder::on(&root)
                .margin_top(top as u32)
                .margin_left(left as u32)
                .margin_right(right as u32)
                .margin_bottom(bottom as u32)
                .build_cartesian_2d(xr.0..xr.1, y)
                .map_err(plot_error)?;
            let grid = ShapeStyle::from(RGBColor(225, 225, 225)).stroke_width(1);
            for &v in &x_ticks {
                let line = vec![(v, y0), (v, y1)];
                chart
                    .draw_series(LineSeries::new(line, grid))
                    .map_err(plot_error)?;
            }
            for &v in &y_ticks {
                let line = vec![(xr.0, v), (xr.1, v)];
                chart
                    .draw_series(LineSeries::new(line, grid))
                    .map_err(plot_error)?;
            }
            let clamp = |(px, py): (f64, f64)| {
                let py = if self.log_y && py <= 0.0 { y0 } else { py };
                (px.clamp(xr.0, xr.1), py.clamp(y0, y1))
            };
            for s in &self.series {
                let style = ShapeStyle::from(rgb(s.color)).stroke_width(s.width.max(1));
                // Non-finite points break the line into runs.
                for run in s
                    .points
                    .split(|p| !(p.0.is_finite() && p.1.is_finite()))
                    .filter(|r| !r.is_empty())
                {
                    let pts: Vec<(f64, f64)> = run.iter().copied().map(clamp).collect();
                    if s.dashed {
                        let dash = 6 + 2 * s.width as i32;
                        chart
                            .draw_series(DashedLineSeries::new(pts, dash, dash - 2, style))
                            .map_err(plot_error)?;
                    } else {
                        chart
                            .draw_series(LineSeries::new(pts, style))
                            .map_err(plot_error)?;
                    }
                }
            }
            let frame = ShapeStyle::from(RGBColor(DARK.0, DARK.1, DARK.2)).stroke_width(1);
            let corners = vec![(xr.0, y0), (xr.1, y0), (xr.1, y1), (xr.0, y1), (xr.0, y0)];
            chart
                .draw_series(LineSeries::new(corners, frame))
                .map_err(plot_error)?;
            root.present().map_err(plot_error)?;
            let at = |p: (f64, f64)| {
                let (px, py) = chart.backend_coord(&p);
                (px as f32, py as f32)
            };
            let xs: Vec<(f32, f32)> = x_ticks.iter().map(|&v| at((v, y0))).collect();
            let ys: Vec<(f32, f32)> = y_ticks.iter().map(|&v| at((xr.0, v))).collect();
            (xs, ys, at((xr.0, y1)), at((xr.1, y0)))
        };
        for (px, rgb) in pm.pixels_mut().iter_mut().zip(buf.chunks_exact(3)) {
            let c = tiny_skia::ColorU8::from_rgba(rgb[0], rgb[1], rgb[2], 255);
            *px = c.premultiply();
        }

        // Text and the legend, with the built-in font.
        let (xs, ys, (ax0, ay0), (ax1, ay1)) = pixel_coords;
        let ink = dark();
        for ((px, py), label) in xs.iter().zip(&x_labels) {
            let tw = text_size(label, SCALE).0;
            draw(
                pm,
                &[(*px, *py), (*px, *py + 5.0)],
                false,
                None,
                Some((ink, 1.0)),
            );
            draw_text(pm, px - 0.5 * tw, py + 9.0, SCALE, label, ink);
        }
        for ((px, py), label) in ys.iter().zip(&y_labels) {
            let (tw, th) = text_size(label, SCALE);
            draw(
                pm,
                &[(*px - 5.0, *py), (*px, *py)],
                false,
                None,
                Some((ink, 1.0)),
            );
            draw_text(pm, px - 9.0 - tw, py - 0.5 * th, SCALE, label, ink);
        }
        draw_text(pm, 14.0, 14.0, SCALE, &self.title, ink);
        draw_text(pm, ax0, ay0 - line_h - 6.0, SCALE, &self.y_label, ink);
        let xl = text_size(&self.x_label, SCALE).0;
        let x_label_y = ay1 + 9.0 + line_h + 10.0;
        draw_text(
            pm,
            0.5 * (ax0 + ax1 - xl),
            x_label_y,
            SCALE,
            &self.x_label,
            ink,
        );
        let (lx, mut ly) = (ax1 + 16.0, ay0 + 4.0);
        for s in &self.series {
            let sample = [(lx, ly + 5.0), (lx + 30.0, ly + 5.0)];
            let c = s.color;
            if s.dashed {
                for k in 0..3 {
                    let a = lx + 11.0 * k as f32;
                    let dash = [(a, ly + 5.0), ((a + 7.0).min(lx + 30.0), ly + 5.0)];
                    draw(pm, &dash, false, None, Some((c, s.width as f32)));
                }
            } else {
                draw(pm, &sample, false, None, Some((c, s.width as f32)));
            }
            draw_text(pm, lx + 38.0, ly, SCALE, &s.label, ink);
            ly += line_h + 6.0;
        }
        ly += 6.0;
        for n in &self.notes {
            draw_text(pm, lx, ly, SCALE, n, ink);
            ly += text_size(n, SCALE).1 + 6.0;
        }
        Ok(())
    }
}

/// Plots side by side in one `width × height` picture, each `width / plots.len()` wide.
pub fn render_row(plots: &[LinePlot], width: u32, height: u32) -> Result<Pixmap, RenderError> {
    let n = plots.len().max(1) as u32;
    let mut pm = Pixmap::new(width, height).ok_or(RenderError::InvalidSize(width, height))?;
    pm.fill(Color::WHITE);
    for (k, p) in plots.iter().enumerate() {
        let panel = p.render(width / n, height)?;
        let x = (k as u32 * (width / n)) as i32;
        pm.draw_pixmap(
            x,
            0,
            panel.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
    }
    Ok(pm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_render_without_fonts() {
        let mut p = LinePlot::new("TITLE", "X", "Y");
        let pts: Vec<(f64, f64)> = (0..50).map(|i| (i as f64, (i as f64).sqrt())).collect();
        p.line("SQRT", Color::from_rgba8(200, 0, 0, 255), pts.clone())
            .dashed = true;
        p.line(
            "BROKEN",
            Color::BLACK,
            vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
        );
        p.notes.push("A NOTE".into());
        let pm = p.render(640, 360).unwrap();
        assert!(pm.pixels().iter().any(|c| c.red() > 150 && c.green() < 50));
        p.log_y = true;
        assert!(p.render(640, 360).is_ok());
        assert!(render_row(&[p.clone(), p.clone()], 1000, 360).is_ok());
        assert!(LinePlot::default().render(300, 200).is_ok());
        assert!(p.render(50, 50).is_err());
    }
}
