//! A heat map of counts per screen tile ([`render_core::TileCounts`]): each tile drawn where it
//! lies in the viewport, filled by its count on the sequential ramp, its number written in it,
//! the busiest tile outlined and named, and the ramp's scale beside the grid. Written as PNG
//! with its numbers as CSV beside (`STEM.png`, `STEM.csv`). The papers' figures that show work
//! per tile are drawn with it (`papers::session::Figure`).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use render_core::TileCounts;

use crate::plot::draw::{err, register_font, FONT};
use crate::plot::style::{ink_on, sequential, BUSIEST_TILE, EMPTY_TILE};

/// The picture's size in pixels, and the grid's longer side.
const SIZE: (u32, u32) = (720, 640);
const GRID: f64 = 480.0;
/// The grid's top-left corner, and the scale bar's left edge and width.
const ORIGIN: (i32, i32) = (50, 70);
const BAR_X: i32 = 570;
const BAR_W: i32 = 26;

/// The rectangles of the tiles in picture pixels, row-major: the viewport scaled into the
/// grid's square, each tile its own pixels' extent (the last column and row may be narrower).
fn tile_rects(c: &TileCounts) -> Vec<[(i32, i32); 2]> {
    let scale = GRID / c.width.max(c.height) as f64;
    let at = |p: u32, side: u32| (p.min(side) as f64 * scale).round() as i32;
    let mut out = vec![];
    for row in 0..c.tiles[1] {
        for col in 0..c.tiles[0] {
            let (x0, x1) = (col * c.tile_size[0], (col + 1) * c.tile_size[0]);
            let (y0, y1) = (row * c.tile_size[1], (row + 1) * c.tile_size[1]);
            out.push([
                (ORIGIN.0 + at(x0, c.width), ORIGIN.1 + at(y0, c.height)),
                (ORIGIN.0 + at(x1, c.width), ORIGIN.1 + at(y1, c.height)),
            ]);
        }
    }
    out
}

/// Text of `size` in `colour`, anchored at `pos`.
fn text(size: u32, colour: &RGBColor, pos: Pos) -> TextStyle<'_> {
    TextStyle::from((FONT, size).into_font())
        .color(colour)
        .pos(pos)
}

fn fill(count: u32, max: u32) -> RGBColor {
    if count == 0 {
        EMPTY_TILE
    } else {
        sequential(count as f64 / max.max(1) as f64)
    }
}

/// Draws the heat map of `c` under `title` on `root`.
fn draw_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    c: &TileCounts,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let black = &BLACK;
    let centre = Pos::new(HPos::Center, VPos::Center);
    let left = Pos::new(HPos::Left, VPos::Center);
    root.fill(&WHITE).map_err(err)?;
    root.draw(&Text::new(
        title.to_string(),
        (SIZE.0 as i32 / 2, 20),
        text(17, black, centre),
    ))
    .map_err(err)?;
    let max = c.counts.iter().copied().max().unwrap_or(0);
    let rects = tile_rects(c);
    for (i, r) in rects.iter().enumerate() {
        let n = c.counts[i];
        let colour = fill(n, max);
        root.draw(&Rectangle::new(*r, colour.filled()))
            .map_err(err)?;
        root.draw(&Rectangle::new(*r, WHITE.stroke_width(1)))
            .map_err(err)?;
        let side = (r[1].0 - r[0].0).min(r[1].1 - r[0].1);
        let mid = ((r[0].0 + r[1].0) / 2, (r[0].1 + r[1].1) / 2);
        let size = (side / 3).clamp(8, 22) as u32;
        let ink = ink_on(colour);
        root.draw(&Text::new(n.to_string(), mid, text(size, &ink, centre)))
            .map_err(err)?;
    }
    // Column numbers above the grid, row numbers left of it (from 1, top left).
    for col in 0..c.tiles[0] {
        let r = rects[col as usize];
        let at = ((r[0].0 + r[1].0) / 2, ORIGIN.1 - 12);
        root.draw(&Text::new(
            (col + 1).to_string(),
            at,
            text(13, black, centre),
        ))
        .map_err(err)?;
    }
    for row in 0..c.tiles[1] {
        let r = rects[(row * c.tiles[0]) as usize];
        let at = (ORIGIN.0 - 14, (r[0].1 + r[1].1) / 2);
        root.draw(&Text::new(
            (row + 1).to_string(),
            at,
            text(13, black, centre),
        ))
        .map_err(err)?;
    }
    let bottom = rects.last().map_or(ORIGIN.1, |r| r[1].1);
    if let Some(b) = c.busiest().filter(|b| b.count > 0) {
        let r = rects[(b.row * c.tiles[0] + b.column) as usize];
        let inset = [(r[0].0 + 2, r[0].1 + 2), (r[1].0 - 2, r[1].1 - 2)];
        root.draw(&Rectangle::new(inset, BUSIEST_TILE.stroke_width(4)))
            .map_err(err)?;
        let line = format!(
            "busiest tile (outlined): row {}, column {}: {} {}{}",
            b.row + 1,
            b.column + 1,
            b.count,
            c.name,
            tie_note(c)
        );
        root.draw(&Text::new(
            line,
            (ORIGIN.0, bottom + 24),
            text(15, black, left),
        ))
        .map_err(err)?;
    }
    let line = format!(
        "{}×{} tiles of {}×{} px over {}×{} px; rows and columns from the top left",
        c.tiles[0], c.tiles[1], c.tile_size[0], c.tile_size[1], c.width, c.height
    );
    root.draw(&Text::new(
        line,
        (ORIGIN.0, bottom + 48),
        text(13, black, left),
    ))
    .map_err(err)?;
    draw_scale(root, c, max)
}

/// The scale beside the grid: the ramp from 1 to the largest count, with ticks, and the
/// colour of a tile that counted nothing.
fn draw_scale<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    c: &TileCounts,
    max: u32,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let font = |size: u32| {
        TextStyle::from((FONT, size).into_font()).pos(Pos::new(HPos::Left, VPos::Center))
    };
    let (top, height) = (ORIGIN.1, GRID as i32 - 40);
    root.draw(&Text::new(
        format!("{} per tile", c.name),
        (BAR_X - 10, top - 12),
        font(13),
    ))
    .map_err(err)?;
    let steps = 96;
    for i in 0..steps {
        // Top = the largest count.
        let t = 1.0 - i as f64 / steps as f64;
        let y0 = top + i * height / steps;
        let y1 = top + (i + 1) * height / steps;
        root.draw(&Rectangle::new(
            [(BAR_X, y0), (BAR_X + BAR_W, y1)],
            sequential(t).filled(),
        ))
        .map_err(err)?;
    }
    root.draw(&Rectangle::new(
        [(BAR_X, top), (BAR_X + BAR_W, top + height)],
        BLACK.stroke_width(1),
    ))
    .map_err(err)?;
    // Ticks at the largest count and at quarters of it, whole numbers, from 1 up.
    let mut ticks: Vec<u32> = (0..=4)
        .map(|q| (max as f64 * q as f64 / 4.0).round() as u32)
        .collect();
    ticks.retain(|&v| v >= 1);
    ticks.dedup();
    for v in ticks {
        let y = top + ((1.0 - v as f64 / max.max(1) as f64) * height as f64).round() as i32;
        root.draw(&PathElement::new(
            vec![(BAR_X + BAR_W, y), (BAR_X + BAR_W + 6, y)],
            BLACK.stroke_width(1),
        ))
        .map_err(err)?;
        root.draw(&Text::new(v.to_string(), (BAR_X + BAR_W + 9, y), font(13)))
            .map_err(err)?;
    }
    let y = top + height + 22;
    root.draw(&Rectangle::new(
        [(BAR_X, y - 9), (BAR_X + BAR_W, y + 9)],
        EMPTY_TILE.filled(),
    ))
    .map_err(err)?;
    root.draw(&Text::new(
        "0".to_string(),
        (BAR_X + BAR_W + 9, y),
        font(13),
    ))
    .map_err(err)?;
    Ok(())
}

/// ` (N more tiles as many)` where the busiest tile shares its count, else nothing.
pub fn tie_note(c: &TileCounts) -> String {
    match c.busiest_ties() {
        0 | 1 => String::new(),
        2 => " (1 more tile as many)".into(),
        n => format!(" ({} more tiles as many)", n - 1),
    }
}

/// The numbers drawn, one line per tile: `row,column,NAME` (from 1, top left).
pub fn csv(c: &TileCounts) -> String {
    let mut out = format!("row,column,{}\n", c.name);
    for row in 0..c.tiles[1] {
        for col in 0..c.tiles[0] {
            let _ = writeln!(out, "{},{},{}", row + 1, col + 1, c.at(col, row));
        }
    }
    out
}

/// Writes `STEM.png` (the heat map of `c` under `title`) and `STEM.csv` (its numbers) into
/// `dir`; returns the PNG's file name.
pub fn save(dir: &Path, stem: &str, title: &str, c: &TileCounts) -> anyhow::Result<String> {
    if let Some(problem) = c.problem() {
        anyhow::bail!("cannot draw the tile counts of {title}: {problem}");
    }
    register_font();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let png = format!("{stem}.png");
    let path = dir.join(&png);
    {
        let root = BitMapBackend::new(&path, SIZE).into_drawing_area();
        draw_on(&root, title, c).with_context(|| format!("writing {}", path.display()))?;
        root.present().map_err(err)?;
    }
    let data = dir.join(format!("{stem}.csv"));
    std::fs::write(&data, csv(c)).with_context(|| format!("cannot write {}", data.display()))?;
    Ok(png)
}

/// The texts an SVG of [`svg`] draws, in order.
pub fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

/// The heat map as SVG text (what the PNG shows, with its text searchable).
pub fn svg(title: &str, c: &TileCounts) -> anyhow::Result<String> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
        draw_on(&root, title, c)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts() -> TileCounts {
        TileCounts {
            name: "passes".into(),
            width: 100,
            height: 100,
            tiles: [3, 3],
            tile_size: [34, 34],
            counts: vec![0, 8, 16, 8, 40, 24, 0, 8, 32],
        }
    }

    #[test]
    fn each_tile_is_drawn_where_it_lies_with_its_number() {
        let c = counts();
        let r = tile_rects(&c);
        // The last column is narrower: 32 of 100 pixels against 34.
        assert!(r[2][1].0 - r[2][0].0 < r[0][1].0 - r[0][0].0);
        assert_eq!(r[8][1], (ORIGIN.0 + GRID as i32, ORIGIN.1 + GRID as i32));
        let drawn = texts(&svg("test", &c).unwrap());
        for n in [
            "40",
            "24",
            "32",
            "busiest tile (outlined): row 2, column 2: 40 passes",
        ] {
            assert!(drawn.iter().any(|t| t == n), "{n} not drawn: {drawn:?}");
        }
        // One count changed: its number and the busiest tile's name change with it.
        let mut d = c.clone();
        d.counts[8] = 41;
        let drawn = texts(&svg("test", &d).unwrap());
        assert!(drawn.iter().any(|t| t == "41"));
        assert!(drawn
            .iter()
            .any(|t| t.ends_with("row 3, column 3: 41 passes")));
        assert_eq!(csv(&d).lines().nth(9), Some("3,3,41"));
        assert_eq!(csv(&c).lines().nth(9), Some("3,3,32"));
        // A tie for the most is said.
        d.counts[4] = 41;
        let drawn = texts(&svg("test", &d).unwrap());
        assert!(drawn
            .iter()
            .any(|t| t.ends_with("row 2, column 2: 41 passes (1 more tile as many)")));
    }

    #[test]
    fn empty_tiles_are_grey_and_the_ramp_rises_with_the_count() {
        assert_eq!(fill(0, 40), EMPTY_TILE);
        assert_ne!(fill(1, 40), EMPTY_TILE);
        let luma = |c: RGBColor| c.0 as u32 + c.1 as u32 + c.2 as u32;
        assert!(luma(fill(10, 40)) < luma(fill(40, 40)));
    }

    #[test]
    fn a_grid_that_does_not_fit_its_viewport_is_refused() {
        let mut c = counts();
        c.counts.pop();
        let dir = tempfile::tempdir().unwrap();
        let e = save(dir.path(), "x", "t", &c).unwrap_err().to_string();
        assert!(e.contains("8 counts"), "{e}");
    }
}
