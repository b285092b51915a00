//! The sweep's chart: time against HDR-FLIP, one labelled point per configuration, the Pareto
//! front as a line, the path tracer's curve (1, 2, 4, ... spp, each at the time all its samples
//! took) on the same axes, and the reference's noise floor as a dashed line. Labels are placed
//! so that none overlaps another, a point or the legend. The same
//! drawing goes to SVG (text as text) and to PNG (text rasterised with an embedded font, so
//! no system fonts are needed).

use super::sweep::SceneSweep;
use crate::image_io;
use ab_glyph::{Font, FontRef, ScaleFont};
use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};
use std::path::Path;
use std::sync::OnceLock;

/// Pixels of the PNG; the SVG has the same user units.
const SIZE: (u32, u32) = (1100, 700);
const FONT: &str = "sans-serif";

/// plotters draws text with fonts registered under a family name; the Ubuntu face that egui's
/// font crate embeds stands in for "sans-serif" (open licence: Ubuntu Font Licence 1.0).
fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_ok()
    });
    if ok { Ok(()) } else { Err(anyhow!("the embedded chart font does not parse")) }
}

/// Writes the chart of one scene's sweep as PNG and SVG.
pub fn write(sweep: &SceneSweep, png: &Path, svg: &Path) -> Result<()> {
    register_font()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
        draw(&root, sweep).map_err(|e| anyhow!("{}: drawing the chart: {e}", svg.display()))?;
    }
    image_io::write_atomic(svg, |tmp| Ok(std::fs::write(tmp, &text)?))?;

    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let font = FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT)?;
        let root = GlyphText { inner: BitMapBackend::with_buffer(&mut rgb, SIZE), font }.into_drawing_area();
        draw(&root, sweep).map_err(|e| anyhow!("{}: drawing the chart: {e}", png.display()))?;
    }
    let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 255]).collect();
    image_io::write_png_rgba8(png, SIZE.0, SIZE.1, &rgba)
}

/// A bitmap backend whose text is rasterised here: each glyph placed at its pen position plus
/// its own bounds (plotters' ab_glyph text leaves the side bearing out, so letters crowd and
/// gap), with kerning, anchors and the axis title's rotation as plotters defines them.
struct GlyphText<'a> {
    inner: BitMapBackend<'a>,
    font: FontRef<'static>,
}

type BackendResult<E> = Result<(), DrawingErrorKind<E>>;

impl GlyphText<'_> {
    /// Width and height of `text` in pixels (pen advance with kerning; ascent to descent).
    fn measure(&self, text: &str, size: f64) -> (i32, i32) {
        let font = self.font.as_scaled(size as f32);
        let mut prev = None;
        let mut x = 0.0;
        for c in text.chars() {
            let id = font.glyph_id(c);
            x += prev.map_or(0.0, |p| font.kern(p, id)) + font.h_advance(id);
            prev = Some(id);
        }
        (x.ceil() as i32, (font.ascent() - font.descent()).ceil() as i32)
    }
}

impl DrawingBackend for GlyphText<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> BackendResult<Self::ErrorType> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> BackendResult<Self::ErrorType> {
        self.inner.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, color: BackendColor) -> BackendResult<Self::ErrorType> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        s: &S,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_line(a, b, s)
    }
    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        s: &S,
        fill: bool,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_rect(a, b, s, fill)
    }
    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        s: &S,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.fill_polygon(vert, s)
    }
    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        c: BackendCoord,
        r: u32,
        s: &S,
        fill: bool,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_circle(c, r, s, fill)
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let (w, h) = self.measure(text, style.size());
        Ok((w as u32, h as u32))
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> BackendResult<Self::ErrorType> {
        let color = style.color();
        let (w, h) = self.measure(text, style.size());
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0,
            HPos::Center => -w / 2,
            HPos::Right => -w,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let transform = style.transform();
        let font = self.font.as_scaled(style.size() as f32);
        let mut coverage = Vec::new();
        let (mut x, mut prev) = (0.0, None);
        for c in text.chars() {
            let id = font.glyph_id(c);
            x += prev.map_or(0.0, |p| font.kern(p, id));
            prev = Some(id);
            let glyph = id.with_scale_and_position(font.scale(), ab_glyph::point(x, font.ascent()));
            x += font.h_advance(id);
            let Some(outline) = font.outline_glyph(glyph) else { continue };
            let b = outline.px_bounds();
            outline.draw(|gx, gy, cov| {
                coverage.push((b.min.x as i32 + gx as i32 + dx, b.min.y as i32 + gy as i32 + dy, cov));
            });
        }
        for (px, py, cov) in coverage {
            let (tx, ty) = transform.transform(px, py);
            let alpha = color.alpha * cov.clamp(0.0, 1.0) as f64;
            self.inner.draw_pixel((pos.0 + tx, pos.1 + ty), BackendColor { alpha, rgb: color.rgb })?;
        }
        Ok(())
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &SceneSweep) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let points: Vec<_> = s.points.iter().filter(|p| p.frame_ms.is_finite() && p.flip > 0.0).collect();
    let path_tracer: Vec<_> = s.path_tracer.iter().filter(|p| p.ms.is_finite() && p.ms > 0.0 && p.flip > 0.0).collect();
    let noise = s.reference.made.noise_flip;
    // Log scales: FLIP spans several factors between the raw and the denoised frames, time
    // two orders of magnitude between one frame and the path tracer's last point.
    let range = |values: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = values.filter(|v| *v > 0.0).fold((f64::MAX, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if lo < hi {
            (lo / 1.25, hi * 1.25)
        } else if hi > 0.0 {
            (hi / 2.0, hi * 2.0)
        } else {
            (0.01, 1.0)
        }
    };
    let (lo, hi) = range(&mut points.iter().map(|p| p.flip).chain(path_tracer.iter().map(|p| p.flip)).chain([noise]));
    let (lo_ms, hi_ms) = range(&mut points.iter().map(|p| p.frame_ms).chain(path_tracer.iter().map(|p| p.ms)));
    let title = format!("{}, {}x{}, {} backend, {}", s.scene_name, s.width, s.height, s.backend, s.device);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin(18)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (lo_ms..hi_ms).log_scale().with_key_points(log_ticks(lo_ms, hi_ms)),
            (lo..hi).log_scale().with_key_points(log_ticks(lo, hi)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(format!(
            "time, ms: one hybrid frame (median of {} round(s) x {} frames after {} warm-up), or all of the path \
             tracer's samples",
            s.rounds.max(1),
            s.timed_frames,
            s.frames - s.timed_frames
        ))
        .y_desc(format!("HDR-FLIP against a {} spp path-traced reference", s.reference.made.spp))
        .y_label_formatter(&|v| tick_label(*v))
        .x_label_formatter(&|v| tick_label(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;

    let front_color = RGBColor(200, 40, 40);
    let front: Vec<(f64, f64)> = s
        .pareto_front
        .iter()
        .filter_map(|n| points.iter().find(|p| &p.name == n))
        .map(|p| (p.frame_ms, p.flip))
        .collect();
    chart
        .draw_series(LineSeries::new(front, front_color.stroke_width(2)))
        .map_err(err)?
        .label("Pareto front of the hybrid frame (after its frames of history)")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], front_color.stroke_width(2)));
    let pt_color = RGBColor(20, 110, 60);
    if !path_tracer.is_empty() {
        chart
            .draw_series(LineSeries::new(path_tracer.iter().map(|p| (p.ms, p.flip)), pt_color.stroke_width(2)))
            .map_err(err)?
            .label("path tracer, 1, 2, 4, ... spp (no history)")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], pt_color.stroke_width(2)));
    }
    if noise > 0.0 {
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new([(lo_ms, noise), (hi_ms, noise)], 6, 4, grey.stroke_width(1)))
            .map_err(err)?
            .label("reference noise (FLIP between its two halves)")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey.stroke_width(1)));
    }
    let on = RGBColor(30, 30, 30);
    let off = RGBColor(110, 110, 170);
    // Every point with its label's text and colour: the configurations, then the path tracer.
    let mut marks: Vec<((f64, f64), String, RGBColor, u32)> = points
        .iter()
        .map(|p| {
            if p.pareto {
                ((p.frame_ms, p.flip), p.name.clone(), on, 5)
            } else {
                ((p.frame_ms, p.flip), p.name.clone(), off, 4)
            }
        })
        .collect();
    marks.extend(path_tracer.iter().map(|p| ((p.ms, p.flip), format!("{} spp", p.spp), pt_color, 4)));
    chart.draw_series(marks.iter().map(|(at, _, color, size)| Circle::new(*at, *size, color.filled()))).map_err(err)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .draw()
        .map_err(err)?;

    // Labels last, placed in pixels so that none overlaps another, a point or the legend.
    let anchors: Vec<(i32, i32)> = marks.iter().map(|(at, ..)| chart.backend_coord(at)).collect();
    let font: TextStyle = (FONT, 13).into();
    let sizes: Vec<(i32, i32)> = marks
        .iter()
        .map(|(_, text, ..)| root.estimate_text_size(text, &font).map(|(w, h)| (w as i32, h as i32)))
        .collect::<Result<_, _>>()
        .map_err(err)?;
    let (xr, yr) = (chart.plotting_area().get_pixel_range().0, chart.plotting_area().get_pixel_range().1);
    let plot = Rect { x: xr.start, y: yr.start, w: xr.end - xr.start, h: yr.end - yr.start };
    let legend_rows = 2 + (!path_tracer.is_empty()) as i32;
    let legend = Rect { x: plot.x + plot.w - 470, y: plot.y, w: 470, h: 12 + 22 * legend_rows };
    for (((_, text, color, _), anchor), place) in
        marks.iter().zip(&anchors).zip(place_labels(&anchors, &sizes, plot, &[legend]))
    {
        let style = font.color(color);
        if needs_leader(&place, *anchor, &anchors) {
            let to = (place.x.clamp(anchor.0.min(place.x + place.w), place.x + place.w), place.y + place.h / 2);
            root.draw(&PathElement::new([*anchor, to], color.mix(0.5).stroke_width(1))).map_err(err)?;
        }
        root.draw(&Text::new(text.clone(), (place.x, place.y), style)).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// A box in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rect {
    x: i32,
    y: i32,
    w: i32,
    h: i32,
}

impl Rect {
    fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.x + o.w && o.x < self.x + self.w && self.y < o.y + o.h && o.y < self.y + self.h
    }

    fn inside(&self, o: &Rect) -> bool {
        self.x >= o.x && self.y >= o.y && self.x + self.w <= o.x + o.w && self.y + self.h <= o.y + o.h
    }

    /// The squared distance from point `p` to the box (0 inside).
    fn distance_sq(&self, (x, y): (i32, i32)) -> i32 {
        let dx = (self.x - x).max(x - (self.x + self.w)).max(0);
        let dy = (self.y - y).max(y - (self.y + self.h)).max(0);
        dx * dx + dy * dy
    }
}

/// Whether the label at `place` needs a thin leader to its point `own` to say whose it is:
/// when it is far from it, or when another of the `anchors` is nearer to it than its own
/// (two configurations a few milliseconds apart: the label of one can sit beside the other).
fn needs_leader(place: &Rect, own: (i32, i32), anchors: &[(i32, i32)]) -> bool {
    let d = place.distance_sq(own);
    d > 40 * 40 || anchors.iter().any(|&a| a != own && place.distance_sq(a) < d)
}

/// Boxes for labels of `sizes` beside the points at `anchors`: for each label in turn, the
/// first spot, on rings of growing distance around its point, that stays inside `area`,
/// overlaps no label placed before, no point and none of `keep_clear`, and lies no nearer to
/// another point than to its own (else the first spot that meets the rest, with a leader). A
/// label that finds none takes its first spot (a chart this crowded has a point on every spot
/// near it).
fn place_labels(anchors: &[(i32, i32)], sizes: &[(i32, i32)], area: Rect, keep_clear: &[Rect]) -> Vec<Rect> {
    const MARK: i32 = 6;
    let mut taken: Vec<Rect> =
        anchors.iter().map(|&(x, y)| Rect { x: x - MARK, y: y - MARK, w: 2 * MARK, h: 2 * MARK }).collect();
    taken.extend_from_slice(keep_clear);
    let mut out = Vec::with_capacity(anchors.len());
    for (&(x, y), &(w, h)) in anchors.iter().zip(sizes) {
        let candidates = || {
            [4, 12, 24, 40, 60, 85, 115].into_iter().flat_map(move |r| {
                [
                    (x + r, y - r - h),
                    (x + r, y + r),
                    (x - r - w, y - r - h),
                    (x - r - w, y + r),
                    (x + r, y - h / 2),
                    (x - r - w, y - h / 2),
                    (x - w / 2, y - r - h),
                    (x - w / 2, y + r),
                ]
                .map(|(cx, cy)| Rect { x: cx, y: cy, w, h })
            })
        };
        let fits = |b: &Rect| b.inside(&area) && !taken.iter().any(|t| t.overlaps(b));
        let own = |b: &Rect| !needs_leader(b, (x, y), anchors);
        let b = candidates()
            .find(|b| fits(b) && own(b))
            .or_else(|| candidates().find(fits))
            .or_else(|| candidates().next())
            .expect("candidates are never empty");
        taken.push(b);
        out.push(b);
    }
    out
}

/// A tick value with as many decimals as its leading digit needs (0.3, not 0.30000000000000004).
fn tick_label(v: f64) -> String {
    let decimals = (-v.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// Tick values for a log axis from `lo` to `hi`: 1, 2 and 5 times the powers of ten, or, when
/// the range holds fewer than four of those, 1 to 9 times them (a range within one decade).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let decades = lo.log10().floor() as i32..=hi.log10().ceil() as i32;
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        decades
            .clone()
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let coarse = ticks(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 4 { coarse } else { ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::sweep::testing::sweep;

    #[test]
    fn writes_png_and_svg_with_the_labels() {
        let s = sweep(&[
            ("d0-s5-b1-r1-t0", 12.0, 0.31, true),
            ("d0-s1-b1-r1", 14.0, 0.12, true),
            ("d4-s5-b1-r1", 30.0, 0.062, true),
            ("d4-s8-b2-r2", 55.0, 0.07, false),
        ]);
        let dir = std::env::temp_dir().join(format!("hybrid-rt-chart-{}", std::process::id()));
        let (png, svg) = (dir.join("c.png"), dir.join("c.svg"));
        write(&s, &png, &svg).unwrap();
        let img = image::open(&png).unwrap();
        assert_eq!((img.width(), img.height()), SIZE);
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        for label in ["d4-s5-b1-r1", "Pareto front", "test scene, 320x180", "8 spp", "path tracer"] {
            assert!(text.contains(label), "the SVG lacks '{label}'");
        }
        if std::env::var_os("HYBRID_RT_KEEP_CHART").is_none() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }

    #[test]
    fn crowded_labels_do_not_overlap() {
        let area = Rect { x: 0, y: 0, w: 1000, h: 600 };
        // Twelve points within a few pixels of each other, and a row of close neighbours.
        let mut anchors: Vec<(i32, i32)> = (0..12).map(|i| (500 + i % 4 * 3, 300 + i / 4 * 3)).collect();
        anchors.extend((0..8).map(|i| (100 + i * 30, 500)));
        let sizes = vec![(90, 14); anchors.len()];
        let legend = Rect { x: 700, y: 0, w: 300, h: 80 };
        let placed = place_labels(&anchors, &sizes, area, &[legend]);
        for (i, a) in placed.iter().enumerate() {
            assert!(a.inside(&area) && !a.overlaps(&legend), "label {i} at {a:?}");
            for (j, b) in placed.iter().enumerate().skip(i + 1) {
                assert!(!a.overlaps(b), "labels {i} {a:?} and {j} {b:?} overlap");
            }
            for &(x, y) in &anchors {
                assert!(!a.overlaps(&Rect { x: x - 6, y: y - 6, w: 12, h: 12 }), "label {i} covers a point");
            }
        }
    }

    #[test]
    fn a_label_nearer_to_another_point_gets_a_leader() {
        // Two points 12 px apart; a label just above the right one.
        let (left, right) = ((100, 100), (112, 100));
        let above_right = Rect { x: 108, y: 80, w: 60, h: 14 };
        assert!(needs_leader(&above_right, left, &[left, right]), "it reads as the right point's label");
        assert!(!needs_leader(&above_right, right, &[left, right]), "beside its own point");
        // Level with both points, left of the left one: the left one's, though the right one
        // is as near along either axis alone.
        let level_left = Rect { x: 40, y: 86, w: 60, h: 14 };
        assert!(needs_leader(&level_left, right, &[left, right]) && !needs_leader(&level_left, left, &[left, right]));
        assert!(needs_leader(&Rect { x: 200, y: 100, w: 60, h: 14 }, right, &[right]), "far from its point");
    }

    #[test]
    fn a_label_is_placed_nearer_its_own_point_than_a_close_neighbour() {
        // Two points 12 px apart (two configurations 10 ms apart), labels wider than the gap.
        let anchors = [(100, 100), (112, 100)];
        let placed = place_labels(&anchors, &[(60, 14); 2], Rect { x: 0, y: 0, w: 400, h: 300 }, &[]);
        for (i, (b, &own)) in placed.iter().zip(&anchors).enumerate() {
            assert!(!needs_leader(b, own, &anchors), "label {i} at {b:?} reads as the other point's");
        }
    }

    #[test]
    fn log_ticks_cover_the_range() {
        assert_eq!(log_ticks(0.05, 0.6), vec![0.05, 0.1, 0.2, 0.5]);
        let fine = log_ticks(0.15, 0.5);
        assert_eq!(fine.len(), 4);
        assert!(fine.iter().all(|v| (0.15..=0.5).contains(v)));
        assert_eq!(fine.iter().map(|&v| tick_label(v)).collect::<Vec<_>>(), ["0.2", "0.3", "0.4", "0.5"]);
        assert_eq!(tick_label(0.05), "0.05");
    }
}
