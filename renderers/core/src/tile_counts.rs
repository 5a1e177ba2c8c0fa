//! Per-tile counts of a frame: a renderer that cuts its viewport into tiles and spends work
//! per tile may report one count per tile ([`crate::Renderer::tile_counts`]); the harness
//! writes them beside the frame's image and reports draw them as a grid.

use serde::{Deserialize, Serialize};

/// One count per tile of a `width`×`height` viewport cut into `tiles[0]` columns and
/// `tiles[1]` rows of `tile_size` pixels (the last column and row may be cut by the edge).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TileCounts {
    /// What is counted per tile, one lower-case word (e.g. `passes`).
    pub name: String,
    /// The viewport in pixels.
    pub width: u32,
    pub height: u32,
    /// Tiles across and down.
    pub tiles: [u32; 2],
    /// A tile's width and height in pixels.
    pub tile_size: [u32; 2],
    /// One count per tile, row by row from the top-left tile.
    pub counts: Vec<u32>,
}

/// The tile with the largest count (the first of them in row-major order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Busiest {
    pub column: u32,
    pub row: u32,
    pub count: u32,
}

impl TileCounts {
    /// What is inconsistent, if anything: a word for the name, tiles that cover the viewport
    /// with no tile wholly outside it, and one count per tile.
    pub fn problem(&self) -> Option<String> {
        let [tx, ty] = self.tiles;
        let [sx, sy] = self.tile_size;
        if self.name.is_empty() || !self.name.chars().all(|c| c.is_ascii_lowercase()) {
            return Some(format!("name {:?} is not one lower-case word", self.name));
        }
        if tx == 0 || ty == 0 || sx == 0 || sy == 0 || self.width == 0 || self.height == 0 {
            return Some(format!(
                "empty grid: {tx}×{ty} tiles of {sx}×{sy} pixels over {}×{}",
                self.width, self.height
            ));
        }
        let covers = |n: u32, size: u32, side: u32| {
            (n as u64) * (size as u64) >= side as u64
                && ((n - 1) as u64) * (size as u64) < side as u64
        };
        if !covers(tx, sx, self.width) || !covers(ty, sy, self.height) {
            return Some(format!(
                "{tx}×{ty} tiles of {sx}×{sy} pixels do not tile a {}×{} viewport",
                self.width, self.height
            ));
        }
        let want = tx as usize * ty as usize;
        (self.counts.len() != want)
            .then(|| format!("{} counts for {tx}×{ty} = {want} tiles", self.counts.len()))
    }

    /// The count of the tile in `column`, `row` (0-based from the top left).
    pub fn at(&self, column: u32, row: u32) -> u32 {
        self.counts[(row * self.tiles[0] + column) as usize]
    }

    /// How many tiles hold the largest count (1 where the busiest tile is alone).
    pub fn busiest_ties(&self) -> usize {
        let max = self.counts.iter().copied().max();
        self.counts.iter().filter(|&&c| Some(c) == max).count()
    }

    /// The tile with the largest count; `None` without tiles.
    pub fn busiest(&self) -> Option<Busiest> {
        let (i, &count) = self
            .counts
            .iter()
            .enumerate()
            .rev()
            .max_by_key(|(_, c)| **c)?;
        let i = i as u32;
        Some(Busiest {
            column: i % self.tiles[0],
            row: i / self.tiles[0],
            count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(counts: Vec<u32>) -> TileCounts {
        TileCounts {
            name: "passes".into(),
            width: 10,
            height: 7,
            tiles: [3, 2],
            tile_size: [4, 4],
            counts,
        }
    }

    #[test]
    fn a_consistent_grid_names_its_first_busiest_tile() {
        let g = grid(vec![1, 9, 2, 9, 0, 3]);
        assert_eq!(g.problem(), None);
        assert_eq!(g.at(2, 1), 3);
        assert_eq!(
            g.busiest(),
            Some(Busiest {
                column: 1,
                row: 0,
                count: 9
            })
        );
        // One count raised moves the busiest tile.
        let mut h = g.clone();
        h.counts[4] = 10;
        assert_eq!(h.busiest().map(|b| (b.column, b.row)), Some((1, 1)));
        assert_eq!((g.busiest_ties(), h.busiest_ties()), (2, 1));
    }

    #[test]
    fn inconsistent_grids_are_named() {
        assert!(grid(vec![1; 5]).problem().unwrap().contains("5 counts"));
        let mut g = grid(vec![1; 6]);
        g.tile_size = [3, 4];
        assert!(g.problem().unwrap().contains("do not tile"));
        g.tile_size = [5, 4];
        assert!(g.problem().unwrap().contains("do not tile"));
        let mut g = grid(vec![1; 6]);
        g.name = "../x".into();
        assert!(g.problem().unwrap().contains("one lower-case word"));
    }
}
