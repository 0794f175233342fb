//! Height grids for terrain patches: CSV (rows along y, columns along x, heights in metres) or
//! grayscale PNG (8 or 16 bit, mapped linearly onto a height range).

use std::path::Path;
#[cfg(test)]
use std::path::PathBuf;

use crate::TerrainError;

/// A regular grid of heights (m) spanning a rectangle; sampled bilinearly.
#[derive(Clone, Debug, PartialEq)]
pub struct Heightmap {
    /// Samples along x (columns).
    pub nx: usize,
    /// Samples along y (rows).
    pub ny: usize,
    /// Heights, row-major: `heights[j * nx + i]` is at column i (x), row j (y).
    pub heights: Vec<f64>,
}

fn hm_err(path: &Path, line: Option<usize>, message: impl Into<String>) -> TerrainError {
    TerrainError::Heightmap { path: path.to_path_buf(), line, message: message.into() }
}

impl Heightmap {
    /// Loads a `.csv` or `.png` file; a PNG needs the height range `(z_black, z_white)` (m).
    pub fn load(path: &Path, png_range: Option<(f64, f64)>) -> Result<Self, TerrainError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("csv") | Some("txt") => Self::from_csv(path),
            Some("png") => {
                let range = png_range.ok_or_else(|| {
                    hm_err(path, None, "a PNG heightmap needs heightmap_range = [z_black, z_white] (m)")
                })?;
                Self::from_png(path, range)
            }
            _ => Err(hm_err(path, None, "unsupported heightmap file: use .csv (heights in m) or .png (grayscale)")),
        }
    }

    /// Reads a CSV grid (commas or whitespace; `#` comments). At least 2×2, rectangular,
    /// every value finite and ≥ 0.
    pub fn from_csv(path: &Path) -> Result<Self, TerrainError> {
        let text = std::fs::read_to_string(path).map_err(|e| hm_err(path, None, format!("cannot read: {e}")))?;
        let mut heights = Vec::new();
        let mut nx = 0;
        let mut ny = 0;
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let row: Result<Vec<f64>, _> = line
                .split(|c: char| c == ',' || c.is_whitespace())
                .filter(|s| !s.is_empty())
                .map(str::parse::<f64>)
                .collect();
            let row = row.map_err(|e| hm_err(path, Some(i + 1), format!("not a number: {e}")))?;
            if ny == 0 {
                nx = row.len();
            } else if row.len() != nx {
                return Err(hm_err(
                    path,
                    Some(i + 1),
                    format!("row has {} values, the first row has {nx}: the grid must be rectangular", row.len()),
                ));
            }
            if let Some(bad) = row.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(hm_err(
                    path,
                    Some(i + 1),
                    format!("height {bad} is not allowed: heights are finite and ≥ 0 m above the container floor"),
                ));
            }
            heights.extend(row);
            ny += 1;
        }
        if nx < 2 || ny < 2 {
            return Err(hm_err(path, None, format!("grid is {nx}×{ny}: at least 2×2 samples are needed")));
        }
        Ok(Self { nx, ny, heights })
    }

    /// Reads a grayscale PNG (8 or 16 bit). Black maps to `range.0`, white to `range.1` (m).
    /// The top image row is the far (max y) edge.
    pub fn from_png(path: &Path, range: (f64, f64)) -> Result<Self, TerrainError> {
        if !(range.0.is_finite() && range.1.is_finite() && range.0 >= 0.0 && range.1 > range.0) {
            return Err(hm_err(path, None, format!("heightmap_range {range:?} must satisfy 0 ≤ z_black < z_white")));
        }
        let file = std::fs::File::open(path).map_err(|e| hm_err(path, None, format!("cannot read: {e}")))?;
        let decoder = png::Decoder::new(std::io::BufReader::new(file));
        let mut reader = decoder.read_info().map_err(|e| hm_err(path, None, format!("not a readable PNG: {e}")))?;
        let size = reader.output_buffer_size().ok_or_else(|| hm_err(path, None, "PNG too large"))?;
        let mut buf = vec![0; size];
        let info = reader.next_frame(&mut buf).map_err(|e| hm_err(path, None, format!("not a readable PNG: {e}")))?;
        let (nx, ny) = (info.width as usize, info.height as usize);
        if info.color_type != png::ColorType::Grayscale {
            return Err(hm_err(
                path,
                None,
                format!("PNG colour type {:?}: a heightmap must be grayscale (8 or 16 bit)", info.color_type),
            ));
        }
        if nx < 2 || ny < 2 {
            return Err(hm_err(path, None, format!("image is {nx}×{ny}: at least 2×2 pixels are needed")));
        }
        let (max, values): (f64, Vec<f64>) = match info.bit_depth {
            png::BitDepth::Eight => (255.0, buf[..nx * ny].iter().map(|&v| f64::from(v)).collect()),
            png::BitDepth::Sixteen => (
                65535.0,
                buf[..2 * nx * ny].chunks_exact(2).map(|c| f64::from(u16::from_be_bytes([c[0], c[1]]))).collect(),
            ),
            other => return Err(hm_err(path, None, format!("PNG bit depth {other:?}: use 8 or 16 bit grayscale"))),
        };
        let mut heights = vec![0.0; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                // Image rows run top to bottom; grid rows run along +y.
                let v = values[(ny - 1 - j) * nx + i];
                heights[j * nx + i] = range.0 + (range.1 - range.0) * v / max;
            }
        }
        Ok(Self { nx, ny, heights })
    }

    /// Height at normalised coordinates `(u, v) ∈ [0, 1]²` (clamped), bilinear.
    pub fn sample(&self, u: f64, v: f64) -> f64 {
        let x = u.clamp(0.0, 1.0) * (self.nx - 1) as f64;
        let y = v.clamp(0.0, 1.0) * (self.ny - 1) as f64;
        let (i0, j0) = ((x.floor() as usize).min(self.nx - 2), (y.floor() as usize).min(self.ny - 2));
        let (fx, fy) = (x - i0 as f64, y - j0 as f64);
        let h = |i: usize, j: usize| self.heights[j * self.nx + i];
        let a = h(i0, j0) * (1.0 - fx) + h(i0 + 1, j0) * fx;
        let b = h(i0, j0 + 1) * (1.0 - fx) + h(i0 + 1, j0 + 1) * fx;
        a * (1.0 - fy) + b * fy
    }

    /// Highest sample (m).
    pub fn max_height(&self) -> f64 {
        self.heights.iter().copied().fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("regolith-hm-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("tmp");
        d.join(name)
    }

    #[test]
    fn csv_loads_and_samples_bilinearly() {
        let p = tmp("a.csv");
        std::fs::write(&p, "# heights\n0.1, 0.2, 0.3\n0.3 0.4 0.5\n").expect("write");
        let h = Heightmap::from_csv(&p).expect("loads");
        assert_eq!((h.nx, h.ny), (3, 2));
        assert!((h.sample(0.0, 0.0) - 0.1).abs() < 1e-12);
        assert!((h.sample(1.0, 1.0) - 0.5).abs() < 1e-12);
        assert!((h.sample(0.5, 0.5) - 0.3).abs() < 1e-12);
        assert!((h.sample(0.25, 0.0) - 0.15).abs() < 1e-12);
    }

    #[test]
    fn csv_errors_name_the_line() {
        let p = tmp("b.csv");
        std::fs::write(&p, "0.1,0.2\n0.1,x\n").expect("write");
        let e = Heightmap::from_csv(&p).expect_err("bad").to_string();
        assert!(e.contains(":2: not a number"), "{e}");
        std::fs::write(&p, "0.1,0.2\n0.1\n").expect("write");
        let e = Heightmap::from_csv(&p).expect_err("ragged").to_string();
        assert!(e.contains(":2: row has 1 values, the first row has 2"), "{e}");
        std::fs::write(&p, "0.1,-0.2\n0.1,0.1\n").expect("write");
        assert!(Heightmap::from_csv(&p).is_err());
    }

    #[test]
    fn png_maps_gray_to_height_with_top_row_at_max_y() {
        let p = tmp("c.png");
        {
            let f = std::fs::File::create(&p).expect("create");
            let mut enc = png::Encoder::new(std::io::BufWriter::new(f), 2, 2);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().expect("header");
            // top row: white, black; bottom row: black, black
            w.write_image_data(&[255, 0, 0, 0]).expect("data");
        }
        let h = Heightmap::from_png(&p, (0.1, 0.5)).expect("loads");
        assert!((h.sample(0.0, 1.0) - 0.5).abs() < 1e-12);
        assert!((h.sample(0.0, 0.0) - 0.1).abs() < 1e-12);
        assert!(Heightmap::load(&p, None).is_err());
    }
}
