//! The evaluation's object sets, by name: built-in objects past every training index, every
//! real mesh of the shared data folder, or a folder of meshes.

use std::path::{Path, PathBuf};

use mvgrasp_geometry::objects::{Category, generate};
use mvgrasp_geometry::{TriangleMesh, load_mesh};

use crate::error::{Error, Result};

/// Real meshes under the shared mesh folder (`../shared/data/meshes`, metres): YCB's boxes,
/// cans and bottle, Dex-Net's test objects, robosuite's and pybullet's objects. The first two
/// (YCB's cracker and sugar boxes) lie flat wider than the hand opens. The household set comes
/// from its manifest ([`household_meshes`]).
pub const REAL_MESHES: [&str; 24] = [
    "ycb/meshes/003_cracker_box_textured.obj",
    "ycb/meshes/004_sugar_box_textured.obj",
    "ycb/meshes/005_tomato_soup_can_textured.obj",
    "ycb/meshes/006_mustard_bottle_textured.obj",
    "ycb/meshes/009_gelatin_box_textured.obj",
    "ycb/meshes/010_potted_meat_can_textured.obj",
    "dexnet/test/models/bar_clamp.obj",
    "dexnet/meshes/example/box.obj",
    "robosuite/objects/meshes/bottle.obj",
    "robosuite/objects/meshes/can.stl",
    "robosuite/objects/meshes/milk.stl",
    "pybullet/objects/mug.urdf",
    "ycb/dishes/evo_bowl_col.obj",
    "ycb/dishes/plate_8in_col.obj",
    "robosuite/objects/meshes/cereal.stl",
    "robosuite/objects/meshes/bread.stl",
    "robosuite/objects/meshes/lemon.stl",
    "dexnet/meshes/example/clown.obj",
    "dexnet/meshes/example/spray.obj",
    "pybullet/duck_vhacd.urdf",
    "pybullet/teddy_vhacd.urdf",
    "pybullet/jenga/jenga.urdf",
    "pybullet/lego/lego.urdf",
    "pybullet/soccerball.urdf",
];

/// The first built-in index of the held-out set: past every training set's 20 per category
/// and the development set's range starts above it ([`DEV_FIRST_INDEX`]).
pub const HELD_OUT_FIRST_INDEX: u32 = 30;

/// The first built-in index of the development set, which settings may be chosen on.
pub const DEV_FIRST_INDEX: u32 = 50;

/// The real development set: every this-many of pybullet's 1,000 `random_urdfs` (procedural
/// "blob" meshes, 1 to 21 cm; none is trained on or in an evaluation set).
pub const DEV_REAL_STRIDE: usize = 20;

/// A set of objects to evaluate on, as named on the command line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ObjectSet {
    /// `held-out`: built-in objects from [`HELD_OUT_FIRST_INDEX`], `per_category` of each.
    HeldOut,
    /// `dev`: built-in objects from [`DEV_FIRST_INDEX`].
    Dev,
    /// `builtin:N`: built-in objects from index N (the ranker's data: 60, past every training,
    /// evaluation and development index).
    Builtin(u32),
    /// `real`: every real mesh of the shared mesh folder ([`REAL_MESHES`] and the household
    /// set's manifest); none when the folder is absent.
    Real,
    /// `dev-real`: real meshes that settings may be chosen on, apart from every evaluation
    /// and training set: pybullet's `random_urdfs` 000, 020, ... 980 ([`DEV_REAL_STRIDE`]);
    /// none when the shared folder is absent.
    DevReal,
    /// `folder:PATH`: every OBJ, STL and URDF file in a folder (not its subfolders).
    Folder(PathBuf),
}

impl std::str::FromStr for ObjectSet {
    type Err = String;

    fn from_str(name: &str) -> std::result::Result<Self, String> {
        match name {
            "held-out" => Ok(Self::HeldOut),
            "dev" => Ok(Self::Dev),
            "real" => Ok(Self::Real),
            "dev-real" => Ok(Self::DevReal),
            _ => {
                if let Some(path) = name.strip_prefix("folder:").filter(|p| !p.is_empty()) {
                    return Ok(Self::Folder(PathBuf::from(path)));
                }
                match name.strip_prefix("builtin:").map(str::parse) {
                    Some(Ok(first)) => Ok(Self::Builtin(first)),
                    _ => Err(format!(
                        "{name:?}: expected held-out, dev, real, dev-real, builtin:N (the first \
                         index) or folder:PATH"
                    )),
                }
            }
        }
    }
}

impl ObjectSet {
    /// Whether it is a set of built-in objects (`held-out`, `dev`, `builtin:N`).
    pub fn is_builtin(&self) -> bool {
        matches!(self, Self::HeldOut | Self::Dev | Self::Builtin(_))
    }

    /// Its name on the command line and in the report.
    pub fn name(&self) -> String {
        match self {
            Self::HeldOut => "held-out".into(),
            Self::Dev => "dev".into(),
            Self::Builtin(first) => format!("builtin:{first}"),
            Self::Real => "real".into(),
            Self::DevReal => "dev-real".into(),
            Self::Folder(path) => format!("folder:{}", path.display()),
        }
    }
}

/// An object of a set, not yet loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjectRef {
    /// Unique within the set: the built-in name, or the file's path under the set's folder.
    pub name: String,
    /// The set's name.
    pub set: String,
    /// The category (built-in), the household manifest's category, or the file's source
    /// folder (`ycb`, `dexnet`, ...).
    pub group: String,
    source: Source,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Source {
    Builtin(Category, u32),
    File(PathBuf),
}

impl ObjectRef {
    /// The object's mesh, metres.
    ///
    /// # Errors
    /// A mesh file that cannot be read (named in the error), or a built-in object that cannot
    /// be made.
    pub fn load(&self) -> Result<TriangleMesh> {
        match &self.source {
            Source::Builtin(category, index) => Ok(generate(*category, *index, 0)?.mesh),
            Source::File(path) => load_mesh(path).map_err(|e| Error::Evaluate {
                problem: format!("{}: {e}", path.display()),
            }),
        }
    }

    /// Whether this is a built-in (procedural) object.
    pub fn is_builtin(&self) -> bool {
        matches!(self.source, Source::Builtin(..))
    }
}

/// The objects of `set`: `per_category` of each built-in category, the real meshes found under
/// `data` (the shared mesh folder), or the folder's mesh files, in a fixed order.
///
/// # Errors
/// A household manifest that cannot be read, or a folder that cannot be listed.
pub fn objects(set: &ObjectSet, per_category: u32, data: &Path) -> Result<Vec<ObjectRef>> {
    let builtin = |first: u32| {
        Category::ALL
            .iter()
            .flat_map(|&category| {
                (first..first + per_category).map(move |index| ObjectRef {
                    name: format!("{}_{index:03}", category.name()),
                    set: set.name(),
                    group: category.name().to_string(),
                    source: Source::Builtin(category, index),
                })
            })
            .collect()
    };
    Ok(match set {
        ObjectSet::HeldOut => builtin(HELD_OUT_FIRST_INDEX),
        ObjectSet::Dev => builtin(DEV_FIRST_INDEX),
        ObjectSet::Builtin(first) => builtin(*first),
        ObjectSet::Real => {
            let mut found: Vec<(String, String)> = REAL_MESHES
                .iter()
                .map(|m| {
                    let source = m.split('/').next().unwrap_or("real");
                    ((*m).to_string(), source.to_string())
                })
                .collect();
            found.extend(household_meshes(data)?);
            found
                .into_iter()
                .map(|(file, group)| (data.join(&file), file, group))
                .filter(|(path, ..)| path.is_file())
                .map(|(path, file, group)| ObjectRef {
                    name: file,
                    set: set.name(),
                    group,
                    source: Source::File(path),
                })
                .collect()
        }
        ObjectSet::DevReal => (0..1000)
            .step_by(DEV_REAL_STRIDE)
            .map(|i| format!("pybullet/random_urdfs/{i:03}/{i:03}.urdf"))
            .map(|file| (data.join(&file), file))
            .filter(|(path, _)| path.is_file())
            .map(|(path, file)| ObjectRef {
                name: file,
                set: set.name(),
                group: "random_urdfs".into(),
                source: Source::File(path),
            })
            .collect(),
        ObjectSet::Folder(folder) => {
            let mut files: Vec<PathBuf> = std::fs::read_dir(folder)
                .map_err(Error::io("list", folder))?
                .filter_map(|entry| entry.ok().map(|e| e.path()))
                .filter(|path| {
                    path.is_file()
                        && path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                            matches!(e.to_ascii_lowercase().as_str(), "obj" | "stl" | "urdf")
                        })
                })
                .collect();
            files.sort();
            files
                .into_iter()
                .map(|path| ObjectRef {
                    name: path
                        .file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
                    set: set.name(),
                    group: "folder".into(),
                    source: Source::File(path),
                })
                .collect()
        }
    })
}

/// The objects of the sets named `names` (as `evaluate --set` names them), in order: of each
/// built-in set `per_category` a category, of each file set at most `max_meshes` (0: all).
///
/// # Errors
/// A name that is not a set (the message says what is expected), or [`objects`]'s.
pub fn objects_of_sets(
    names: &[String],
    per_category: u32,
    data: &Path,
    max_meshes: usize,
) -> Result<Vec<ObjectRef>> {
    let mut found = Vec::new();
    for name in names {
        let set: ObjectSet = name.parse().map_err(|e| Error::Evaluate {
            problem: format!("set {e}"),
        })?;
        let mut of_set = objects(&set, per_category, data)?;
        if max_meshes > 0 && !set.is_builtin() {
            of_set.truncate(max_meshes);
        }
        found.extend(of_set);
    }
    Ok(found)
}

/// The household set's mesh files under `data` with their categories, from
/// `household/manifest.json` (none when the folder has no manifest).
///
/// # Errors
/// A manifest that is not JSON with an `objects` list of `file`s.
pub fn household_meshes(data: &Path) -> Result<Vec<(String, String)>> {
    let path = data.join("household/manifest.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    let manifest: serde_json::Value =
        serde_json::from_str(&text).map_err(Error::json("read", "manifest", &path))?;
    let problem = |what: &str| Error::Evaluate {
        problem: format!("{}: {what}", path.display()),
    };
    let objects = manifest["objects"]
        .as_array()
        .ok_or_else(|| problem("no \"objects\" list"))?;
    objects
        .iter()
        .map(|o| {
            let file = o["file"]
                .as_str()
                .ok_or_else(|| problem("an object without \"file\""))?;
            let category = o["category"].as_str().unwrap_or("household");
            Ok((format!("household/{file}"), format!("household {category}")))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_parse_by_name_and_a_wrong_name_says_what_is_expected() {
        assert_eq!("held-out".parse(), Ok(ObjectSet::HeldOut));
        assert_eq!(
            "folder:/tmp/x".parse(),
            Ok(ObjectSet::Folder(PathBuf::from("/tmp/x")))
        );
        assert_eq!("builtin:60".parse(), Ok(ObjectSet::Builtin(60)));
        assert_eq!(ObjectSet::Builtin(60).name(), "builtin:60");
        let wrong = "heldout".parse::<ObjectSet>().unwrap_err();
        assert!(
            wrong.contains(
                "held-out, dev, real, dev-real, builtin:N (the first index) or folder:PATH"
            ),
            "{wrong}"
        );
        assert!("builtin:sixty".parse::<ObjectSet>().is_err());
        let set = objects(&ObjectSet::Builtin(60), 2, Path::new("/nonexistent")).unwrap();
        assert_eq!(set.len(), 2 * Category::ALL.len());
        assert_eq!(set[1].name, format!("{}_061", Category::ALL[0].name()));
    }

    #[test]
    fn the_real_development_set_takes_every_twentieth_random_urdf_found() {
        let data = tempfile::tempdir().unwrap();
        for i in ["000", "001", "020", "040"] {
            let dir = data.path().join("pybullet/random_urdfs").join(i);
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join(format!("{i}.urdf")), "<robot/>").unwrap();
        }
        // 040's folder without its file: not found, left out.
        std::fs::remove_file(data.path().join("pybullet/random_urdfs/040/040.urdf")).unwrap();
        let set = objects(&ObjectSet::DevReal, 5, data.path()).unwrap();
        let names: Vec<_> = set.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "pybullet/random_urdfs/000/000.urdf",
                "pybullet/random_urdfs/020/020.urdf"
            ]
        );
        assert!(set.iter().all(|o| o.set == "dev-real" && !o.is_builtin()));
        assert!(
            objects(&ObjectSet::DevReal, 5, Path::new("/nonexistent"))
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn the_held_out_set_starts_past_the_development_set_and_names_each_object_once() {
        let set = objects(&ObjectSet::HeldOut, 2, Path::new("/nonexistent")).unwrap();
        assert_eq!(set.len(), 2 * Category::ALL.len());
        let mut names: Vec<_> = set.iter().map(|o| o.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), set.len());
        assert!(set.iter().all(ObjectRef::is_builtin));
        assert!(set[0].name.ends_with("_030"), "{}", set[0].name);
        assert!(
            objects(&ObjectSet::Real, 1, Path::new("/nonexistent"))
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn a_folder_that_is_not_there_is_an_error_naming_it() {
        let e = objects(
            &ObjectSet::Folder("/nonexistent/meshes".into()),
            1,
            Path::new("."),
        )
        .unwrap_err();
        assert!(e.to_string().contains("/nonexistent/meshes"), "{e}");
    }
}
