//! Named data sets usable on the command line: the papers' public data sets (resolved from a
//! data directory), generator specs (`box:200k`, `shell:1m`, …) and plain file paths.
//!
//! The data directory is `--data-dir`, else the environment variable `TETBENCH_DATA`, else
//! `../shared/datasets` relative to the current directory, else `shared/datasets` beside one
//! of the executable's ancestor folders (a binary under `<root>/main/target/…` finds
//! `<root>/shared/datasets`), else the same path relative to this crate's source.

use std::path::{Path, PathBuf};

use crate::dataset::{Dataset, LazyDataset, LoadOptions, Plot3dField};
use crate::error::{ErrorKind, LoadError};

/// Where public copies of the files live (shown when one is missing).
const VTK_DATA: &str =
    "VTK's data repository, Data/ (e.g. https://github.com/pyvista/vtk-data/tree/master/Data)";
const VISTRAILS: &str =
    "the VisTrails examples (https://github.com/VisTrails/VisTrails, examples/data/spx.vtk)";

pub use crate::entry::Entry;

/// A named file data set.
struct Named {
    name: &'static str,
    description: &'static str,
    /// The file to load (PLOT3D: the XYZ file) and any companions (the Q file).
    files: &'static [&'static str],
    origin: &'static str,
    paper: &'static str,
    /// PLOT3D field used unless the caller asks for another.
    field: Option<Plot3dField>,
}

const NAMED: &[Named] = &[
    Named {
        name: "bluntfin",
        description: "Blunt Fin (NASA), PLOT3D 40×32×32 curvilinear grid, density: 40,960 points / 187,395 tets",
        files: &["bluntfinxyz.bin", "bluntfinq.bin"],
        origin: VTK_DATA,
        paper: "the papers' Blunt Fin (187,395 tets)",
        field: Some(Plot3dField::Density),
    },
    Named {
        name: "comb",
        description: "Combustion Chamber, PLOT3D 57×33×25, density: 47,025 points / 215,040 tets",
        files: &["combxyz.bin", "combq.bin"],
        origin: VTK_DATA,
        paper: "the papers' Combustion Chamber (215,040 tets)",
        field: Some(Plot3dField::Density),
    },
    Named {
        name: "post",
        description: "Liquid Oxygen Post, PLOT3D 38×76×38 with IBLANK, velocity magnitude (ρ = 1 everywhere): 109,744 points / 513,375 tets",
        files: &["postxyz.bin", "postq.bin"],
        origin: VTK_DATA,
        paper: "the papers' LOx Post (513,375 tets)",
        field: Some(Plot3dField::VelocityMagnitude),
    },
    Named {
        name: "spx",
        description: "SPX (Électricité de France), legacy VTK tets: 2,896 points / 12,936 tets, non-convex",
        files: &["spx.vtk"],
        origin: VISTRAILS,
        paper: "SPX of the HAVS/ZSWEEP distributions",
        field: None,
    },
    Named {
        name: "tetramesh",
        description: "VTK sample tet mesh (legacy ASCII): 55 points / 160 tets",
        files: &["tetraMesh.vtk"],
        origin: VTK_DATA,
        paper: "VTK sample (reader test)",
        field: None,
    },
    Named {
        name: "tetrahedron",
        description: "VTK sample (XML .vtu, raw appended, UInt64 header): 35 points / 96 tets",
        files: &["Tetrahedron.vtu"],
        origin: VTK_DATA,
        paper: "VTK sample (reader test)",
        field: None,
    },
    Named {
        name: "ironprot",
        description: "Iron protein, 68³ unsigned-char volume (legacy BINARY STRUCTURED_POINTS): 1,503,815 tets",
        files: &["ironProt.vtk"],
        origin: VTK_DATA,
        paper: "regular volume (splatting comparisons)",
        field: None,
    },
    Named {
        name: "headmr",
        description: "MR head, 48×62×42 unsigned-char MetaImage volume",
        files: &["HeadMRVolume.mhd", "HeadMRVolume.raw"],
        origin: VTK_DATA,
        paper: "regular volume (splatting comparisons)",
        field: None,
    },
];

/// Generator specs listed by [`Registry::entries`] (any size works; these are examples).
const GENERATED: &[(&str, &str)] = &[
    (
        "box:200k",
        "stand-in for mid-size convex meshes (e.g. Blunt Fin class)",
    ),
    (
        "shell:1m",
        "non-convex stand-in (rays re-enter) for the unavailable F117/fighter class",
    ),
    ("tunnels:1m", "non-convex stand-in with many re-entries"),
    (
        "slivers:50k",
        "sliver-rich mesh for the HAVS k-buffer analysis",
    ),
];

pub use crate::data_dir::{default_data_dir, test_data_file};

/// What a name resolves to, before anything is loaded.
enum Source {
    Named(&'static Named),
    Generated,
    File(PathBuf),
    /// A stand-in or `NAME@splitN` ([`crate::standins`]).
    StandIn,
    /// A generated volume (`vol:N`, [`crate::gen_volume`]).
    Volume,
}

/// Resolves names, specs and paths to data sets.
#[derive(Debug, Clone, Default)]
pub struct Registry {
    pub data_dir: Option<PathBuf>,
}

impl Registry {
    /// `None` uses [`default_data_dir`].
    pub fn new(data_dir: Option<PathBuf>) -> Registry {
        Registry {
            data_dir: data_dir.or_else(default_data_dir),
        }
    }

    fn file(&self, f: &str) -> Option<PathBuf> {
        self.data_dir.as_ref().map(|d| d.join(f))
    }

    /// Every named data set and example generator spec, with whether its files are present.
    pub fn entries(&self) -> Vec<Entry> {
        let mut out: Vec<Entry> = NAMED
            .iter()
            .map(|n| Entry {
                name: n.name.into(),
                description: n.description.into(),
                files: n.files.iter().map(|f| f.to_string()).collect(),
                present: n
                    .files
                    .iter()
                    .all(|f| self.file(f).is_some_and(|p| p.is_file())),
                paper: n.paper,
            })
            .collect();
        let derived = crate::standins::entries(&out);
        out.extend(derived);
        for (spec, paper) in GENERATED {
            let kind = crate::generate::parse_spec(spec)
                .map(|s| s.kind.description())
                .unwrap_or_default();
            out.push(Entry {
                name: spec.to_string(),
                description: format!("generated: {kind}"),
                files: vec![],
                present: true,
                paper,
            });
        }
        out.push(Entry {
            name: "vol:64".into(),
            description: "generated volume: smooth compact bumps on a 64³ grid (any vol:N or vol:NXxNYxNZ[:eff=COUNT])".into(),
            files: vec![],
            present: true,
            paper: "regular volume for splatting (Grau & Tost 2007)",
        });
        out
    }

    /// Loads a named data set (case-insensitive), a generator spec (`KIND:SIZE[:opts]`, seed 1
    /// unless the spec says `seed=N`) or a file path.
    pub fn resolve(&self, name_or_path: &str, options: &LoadOptions) -> Result<Dataset, LoadError> {
        let key = name_or_path.trim();
        match self.locate(key)? {
            Source::Named(n) => self.load_named(n, options),
            Source::Generated => {
                let mesh = crate::generate::from_spec(key, 1)?;
                if let Some(want) = &options.scalar {
                    if *want != mesh.scalar_name {
                        return Err(LoadError::new(
                            key,
                            ErrorKind::MissingArray {
                                name: want.clone(),
                                available: vec![mesh.scalar_name.clone()],
                            },
                        ));
                    }
                }
                Ok(Dataset {
                    mesh,
                    volume: None,
                    source: key.to_string(),
                })
            }
            Source::File(p) => crate::load::load(&p, options),
            Source::Volume => {
                let mesh = crate::gen_volume::from_volume_spec(key)?;
                let volume = mesh.source_grid.clone();
                Ok(Dataset {
                    mesh,
                    volume,
                    source: key.to_string(),
                })
            }
            Source::StandIn => crate::standins::resolve(&|k, o| self.resolve(k, o), key, options)
                .unwrap_or_else(|| {
                    Err(LoadError::new(
                        key,
                        ErrorKind::Io("not a stand-in or split modifier".into()),
                    ))
                }),
        }
    }

    /// [`Self::resolve`], leaving generated volumes (`vol:N`, `fuel`, `brain`, the splatting
    /// stand-ins) as voxels whose tets are split only when something asks for them: what a run
    /// holds, so that one measuring only voxel renderers never splits them.
    pub fn resolve_lazy(
        &self,
        name_or_path: &str,
        options: &LoadOptions,
    ) -> Result<LazyDataset, LoadError> {
        let key = name_or_path.trim();
        match self.locate(key)? {
            Source::Volume => {
                let volume = crate::gen_volume::voxels_from_volume_spec(key)?;
                Ok(LazyDataset::from_voxels(volume, key))
            }
            Source::StandIn => {
                crate::standins::resolve_lazy(&|k, o| self.resolve(k, o), key, options)
                    .unwrap_or_else(|| {
                        Err(LoadError::new(
                            key,
                            ErrorKind::Io("not a stand-in or split modifier".into()),
                        ))
                    })
            }
            _ => self.resolve(key, options).map(Into::into),
        }
    }

    /// Checks, without loading anything, that `name_or_path` names something [`Self::resolve`]
    /// can load: a named data set whose files are all in the data directory, a generator spec
    /// that parses, or an existing file. Lets a run refuse a typo before measuring anything.
    pub fn check(&self, name_or_path: &str) -> Result<(), LoadError> {
        self.locate(name_or_path.trim()).map(|_| ())
    }

    fn locate(&self, key: &str) -> Result<Source, LoadError> {
        if let Some(n) = NAMED.iter().find(|n| n.name.eq_ignore_ascii_case(key)) {
            self.named_files(n)?;
            return Ok(Source::Named(n));
        }
        // The papers' derived data sets and stand-ins (spx1, spx2, fuel, …) and `NAME@splitN`
        // (whose base must resolve in turn).
        if let Some((base, modifier)) = key.rsplit_once('@') {
            if crate::split::parse_modifier(modifier).is_some() {
                self.locate(base)?;
                return Ok(Source::StandIn);
            }
        }
        if crate::standins::find(key).is_some() {
            return Ok(Source::StandIn);
        }
        if crate::gen_volume::is_volume_spec(key) {
            crate::gen_volume::parse_volume_spec(key).map_err(|k| LoadError::new(key, k))?;
            return Ok(Source::Volume);
        }
        if crate::generate::is_spec(key) {
            crate::generate::parse_spec(key).map_err(|k| LoadError::new(key, k))?;
            return Ok(Source::Generated);
        }
        let path = Path::new(key);
        if path.exists() {
            return Ok(Source::File(path.to_path_buf()));
        }
        // A bare file name may live in the data directory.
        if let Some(p) = self
            .file(key)
            .filter(|p| p.is_file() && !path.is_absolute())
        {
            return Ok(Source::File(p));
        }
        let known: Vec<&str> = NAMED.iter().map(|n| n.name).collect();
        Err(LoadError::new(
            key,
            ErrorKind::Io(format!(
                "no such file, named data set ({}) or generator spec (box|shell|tunnels|slivers|onion:SIZE[:field=…][:seed=…], vol:N[:eff=…], standin:NAME); `tetbench datasets list` shows them",
                known.join(", ")
            )),
        ))
    }

    /// The paths of a named data set's files, or which one is missing and where it comes from.
    fn named_files(&self, n: &Named) -> Result<Vec<PathBuf>, LoadError> {
        let missing = |file: &str, where_: String| {
            LoadError::new(
                where_,
                ErrorKind::MissingDataFile {
                    dataset: n.name.into(),
                    file: file.into(),
                    origin: n.origin.into(),
                },
            )
        };
        let Some(dir) = &self.data_dir else {
            return Err(missing(
                &n.files.join(" + "),
                "(no data directory found: use --data-dir or set TETBENCH_DATA)".into(),
            ));
        };
        n.files
            .iter()
            .map(|f| {
                let p = dir.join(f);
                if p.is_file() {
                    Ok(p)
                } else {
                    Err(missing(f, p.display().to_string()))
                }
            })
            .collect()
    }

    fn load_named(&self, n: &Named, options: &LoadOptions) -> Result<Dataset, LoadError> {
        let files = self.named_files(n)?;
        let mut opts = options.clone();
        if n.field.is_some() {
            if opts.q_file.is_none() && files.len() > 1 {
                opts.q_file = Some(files[1].clone());
            }
            if opts.plot3d_field.is_none() && opts.scalar.is_none() {
                opts.plot3d_field = n.field;
            }
        }
        let mut ds = crate::load::load(&files[0], &opts)?;
        ds.mesh.name = n.name.to_string();
        Ok(ds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_file_names_it_and_its_origin() {
        let dir = tempfile::tempdir().unwrap();
        let reg = Registry::new(Some(dir.path().to_path_buf()));
        let err = reg
            .resolve("bluntfin", &LoadOptions::default())
            .unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(&err.kind, ErrorKind::MissingDataFile { file, .. } if file == "bluntfinxyz.bin"),
            "{msg}"
        );
        assert!(msg.contains("vtk-data"), "{msg}");
        let err = reg.resolve("SPX", &LoadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("VisTrails"), "{err}");
        let entries = reg.entries();
        assert!(entries.iter().any(|e| e.name == "post" && !e.present));
        assert!(entries.iter().any(|e| e.name == "shell:1m" && e.present));
    }

    #[test]
    fn specs_and_unknown_names() {
        let reg = Registry::new(None);
        let ds = reg
            .resolve("box:1k:field=linear", &LoadOptions::default())
            .unwrap();
        assert_eq!(ds.mesh.scalar_name, "linear");
        assert_eq!(ds.source, "box:1k:field=linear");
        let err = reg
            .resolve("no-such-thing", &LoadOptions::default())
            .unwrap_err();
        assert!(matches!(err.kind, ErrorKind::Io(_)));
        let err = reg
            .resolve("box:lots", &LoadOptions::default())
            .unwrap_err();
        assert!(matches!(err.kind, ErrorKind::Syntax { .. }));
    }

    #[test]
    fn volumes_resolve_lazily_and_hold_their_values_once() {
        let reg = Registry::new(None);
        let options = LoadOptions::default();
        for spec in ["vol:12x10x9:eff=200", "fuel"] {
            let lazy = reg.resolve_lazy(spec, &options).unwrap();
            let volume = lazy.voxels().expect("a generated volume stays voxels");
            // Only the volume holds the grid: no split mesh, no second copy.
            assert_eq!(std::sync::Arc::strong_count(volume.grid()), 1, "{spec}");
            assert!(!lazy.tets_built(), "{spec}");
            let eager = reg.resolve(spec, &options).unwrap();
            assert_eq!(lazy.num_tets(), eager.mesh.num_tets(), "{spec}");
            assert_eq!(lazy.num_points(), eager.mesh.num_points(), "{spec}");
            assert_eq!(lazy.bounds(), eager.mesh.bounds(), "{spec}");
            assert_eq!(lazy.scalar_range(), eager.mesh.scalar_range(), "{spec}");
            assert_eq!(lazy.mesh().unwrap().tets, eager.mesh.tets, "{spec}");
            // The eager data set's grid and its mesh's source grid are one allocation.
            let (grid, source) = (eager.volume.as_ref(), eager.mesh.source_grid.as_ref());
            assert!(
                std::sync::Arc::ptr_eq(grid.unwrap(), source.unwrap()),
                "{spec}"
            );
        }
        let mesh = reg.resolve_lazy("box:1k", &options).unwrap();
        assert!(mesh.voxels().is_none() && mesh.tets_built());
    }
}
