//! The files a spec names — scenes (TOML with its OBJ meshes, or AFF with its includes) and points
//! CSVs — loaded once per run, shared by every point that names them, and hashed, so the metadata
//! pins their content and `--resume` and `raycost merge` can refuse a run whose inputs changed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use super::kind::ConfigError;
use crate::error::InputError;
use crate::lt::Scene;
use crate::output::meta::InputFile;
use crate::spec::KeyError;

/// Points read from a CSV: centres and unit normals.
#[derive(Debug, PartialEq)]
pub struct PointsFile {
    /// The file.
    pub path: PathBuf,
    /// Points.
    pub centers: Vec<DVec3>,
    /// Unit normals.
    pub normals: Vec<DVec3>,
}

/// A scene file, loaded.
#[derive(Debug)]
pub struct SceneFile {
    /// The file as resolved.
    pub path: PathBuf,
    /// The scene.
    pub scene: Scene,
}

/// The input files of one run.
#[derive(Debug, Default)]
pub struct Inputs {
    /// The spec's folder: relative paths start there.
    dir: PathBuf,
    scenes: BTreeMap<PathBuf, Arc<SceneFile>>,
    points: BTreeMap<PathBuf, Arc<PointsFile>>,
    files: BTreeMap<PathBuf, InputFile>,
}

impl Inputs {
    /// Inputs relative to the spec's folder `dir`.
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            ..Self::default()
        }
    }

    /// Resolves `relative` (named by spec key `key`) against the spec's folder; it must be a file.
    pub fn file(&self, key: &str, relative: &str) -> Result<PathBuf, ConfigError> {
        let path = self.dir.join(relative);
        match crate::error::regular_input(&path) {
            Ok(()) => {}
            Err(why) if why == "no such file" => {
                let aff = matches!(
                    path.extension().and_then(|x| x.to_str()),
                    Some("aff" | "nff")
                );
                let hint = if aff {
                    format!("; {}", crate::lt::aff::BART_HINT)
                } else {
                    String::new()
                };
                return Err(KeyError::new(
                    key,
                    format!(
                        "{}: no such file (paths are relative to the spec's folder){hint}",
                        path.display()
                    ),
                )
                .into());
            }
            Err(why) => return Err(KeyError::new(key, format!("{}: {why}", path.display())).into()),
        }
        Ok(path)
    }

    /// The scene file named by `key`, loaded once for the whole run.
    pub fn scene(&mut self, key: &str, relative: &str) -> Result<Arc<SceneFile>, ConfigError> {
        let path = self.file(key, relative)?;
        if let Some(s) = self.scenes.get(&path) {
            return Ok(Arc::clone(s));
        }
        // The scene's own error (its file, line and key) is told at the spec key that names it.
        let scene = Scene::load(&path).map_err(|e| KeyError::new(key, e.to_string()))?;
        let role = match path.extension().and_then(|x| x.to_str()) {
            Some("aff" | "nff") => "aff",
            _ => "scene",
        };
        self.record(&path, role)?;
        for (file, role) in scene.sources() {
            self.record(&file, role)?;
        }
        let s = Arc::new(SceneFile {
            path: path.clone(),
            scene,
        });
        self.scenes.insert(path, Arc::clone(&s));
        Ok(s)
    }

    /// The points CSV named by `key`, read once for the whole run.
    pub fn points(&mut self, key: &str, relative: &str) -> Result<Arc<PointsFile>, ConfigError> {
        let path = self.file(key, relative)?;
        if let Some(p) = self.points.get(&path) {
            return Ok(Arc::clone(p));
        }
        let (centers, normals) = crate::detp::surface_points::read_points_csv(&path)
            .map_err(|e| KeyError::new(key, e.to_string()))?;
        self.record(&path, "points")?;
        let p = Arc::new(PointsFile {
            path: path.clone(),
            centers,
            normals,
        });
        self.points.insert(path, Arc::clone(&p));
        Ok(p)
    }

    fn record(&mut self, path: &Path, role: &str) -> Result<(), ConfigError> {
        if !self.files.contains_key(path) {
            let f = InputFile::hash(path, role, &self.dir).map_err(|e| {
                InputError::new(path.display().to_string(), format!("cannot read: {e}"))
            })?;
            self.files.insert(path.to_path_buf(), f);
        }
        Ok(())
    }

    /// Every file read, with its content hash, by path.
    pub fn files(&self) -> Vec<InputFile> {
        self.files.values().cloned().collect()
    }
}
