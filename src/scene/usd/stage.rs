//! The one file that speaks to the `openusd` crate (pinned at 0.6.0): it
//! opens a stage (`.usda`, `.usdc`, `.usdz`, composition included) and
//! answers the import's questions in this crate's own types (glam values,
//! `String` paths and messages), so that moving to another version of the
//! crate touches this file alone.
//!
//! What 0.6 leaves to its user is done by the import, not here: schema
//! fallback values (`schema`), world transforms (`xform`), inherited
//! bindings, primvar indices and triangulation (`geometry`).

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat4, DQuat, DVec2, DVec3, DVec4};
use openusd::{ar, sdf, usd};

/// A composed stage, read at one time code at a time.
pub(super) struct Stage {
    stage: usd::Stage,
    /// `--asset-path`'s directories (the resolver's search paths).
    search_paths: Vec<PathBuf>,
}

/// An asset path as the stage resolves it (an attribute of type `asset`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Asset {
    /// As authored, for messages.
    pub authored: String,
    /// Where USD's resolution puts it: the authored path anchored to the
    /// layer that authored the value (a file, or `package.usdz[member]`),
    /// or found on a search path. It may not exist.
    pub location: String,
}

/// What a prim is, as the import needs it.
#[derive(Debug, Clone, Default)]
pub(super) struct PrimInfo {
    /// The schema's type name (`Mesh`, `RectLight`...); empty for a typeless prim.
    pub type_name: String,
    /// Applied API schemas (`ShapingAPI`, `MaterialBindingAPI`...).
    pub api_schemas: Vec<String>,
    /// Whether it is drawn at all: active, defined (`def`, not only `over`)
    /// and not abstract (`class`).
    pub present: bool,
    /// The prototype an instanceable prim shares, when it is an instance.
    pub prototype: Option<String>,
}

/// A message from the reader, as text.
pub(super) type Failure = String;

fn failure(e: &impl std::fmt::Display) -> Failure {
    format!("{e:#}")
}

/// The largest array an attribute may hold (2^28 elements): a corrupt or
/// hostile file's counts are refused before anything is made of them.
pub(super) const MAX_ARRAY: usize = 1 << 28;

/// `prim.name`, once both are checked well-formed (see [`checked`]).
fn attribute_path(prim: &str, name: &str) -> Result<String, Failure> {
    let name_ok = !name.is_empty() && name.split(':').all(identifier);
    if !name_ok {
        return Err(format!("'{name}' is not a property name"));
    }
    Ok(format!("{}.{name}", checked(prim)?))
}

/// Whether `name` is a USD identifier: a letter or `_`, then letters,
/// digits and `_`.
fn identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `path` if it is an absolute prim path of identifiers (`/World/Ball`):
/// the reader does not check the paths it is handed, and a malformed one
/// (a connection a corrupt file authors, say) sent it into unbounded
/// recursion in the fuzzer.
fn checked(path: &str) -> Result<&str, Failure> {
    let ok = path == "/" || (path.starts_with('/') && path[1..].split('/').all(identifier));
    if ok {
        Ok(path)
    } else {
        Err(format!("'{path}' is not a prim path"))
    }
}

/// USD's default resolver, with every file checked before the reader sees
/// it: only regular files (a FIFO blocks, a device never ends) of at most
/// [`MAX_FILE_BYTES`](crate::util::file::MAX_FILE_BYTES), and only packages
/// whose members are stored as the `.usdz` format defines them
/// (uncompressed, and no larger than the package): the reader inflates a
/// member whole, so a deflated member of 2.5 GiB in a package of 2.6 MB
/// took 5.3 GB before its error.
struct CheckedResolver {
    inner: ar::DefaultResolver,
    /// Where a search path (a relative asset path not starting `./` or
    /// `../`) is looked for when it is not beside the layer that names it,
    /// in order: `--asset-path`'s directories, then
    /// `PXR_AR_DEFAULT_SEARCH_PATH`'s (USD's default resolver's own).
    search_paths: Vec<PathBuf>,
}

/// Whether `asset` is what USD's default resolver calls a search path: a
/// relative path that does not start `./` or `../` (`textures/wood.png`).
fn is_search_path(asset: &str) -> bool {
    !asset.is_empty()
        && !Path::new(asset).is_absolute()
        && !asset.starts_with("./")
        && !asset.starts_with("../")
        && !ar::is_package_relative_path(asset)
}

impl CheckedResolver {
    /// Refuses `path` unless it is a regular file within the size limit and,
    /// when it is a zip archive (a `.usdz` package), every member is stored
    /// uncompressed within the package's own size.
    fn check_file(path: &Path) -> std::io::Result<()> {
        let invalid = |message: String| std::io::Error::new(std::io::ErrorKind::InvalidData, message);
        let file = crate::util::file::open_regular(path)?;
        let length = file.metadata()?.len();
        if length > crate::util::file::MAX_FILE_BYTES {
            return Err(invalid(format!(
                "'{}' holds {length} bytes, more than {}",
                path.display(),
                crate::util::file::MAX_FILE_BYTES
            )));
        }
        let mut magic = [0u8; 4];
        let mut reader = std::io::BufReader::new(file);
        let zip = reader.read_exact(&mut magic).is_ok() && magic == *b"PK\x03\x04";
        if !zip {
            return Ok(());
        }
        let mut archive = zip::ZipArchive::new(reader.into_inner())
            .map_err(|e| invalid(format!("'{}' is not a readable package: {e}", path.display())))?;
        for i in 0..archive.len() {
            let member =
                archive.by_index_raw(i).map_err(|e| invalid(format!("'{}': member {i}: {e}", path.display())))?;
            if member.compression() != zip::CompressionMethod::Stored {
                return Err(invalid(format!(
                    "'{}': member '{}' is compressed ({}); a .usdz package stores its members uncompressed",
                    path.display(),
                    member.name(),
                    member.compression()
                )));
            }
            if member.size() > length {
                return Err(invalid(format!(
                    "'{}': member '{}' claims {} bytes, more than the package holds",
                    path.display(),
                    member.name(),
                    member.size()
                )));
            }
        }
        Ok(())
    }
}

impl ar::Resolver for CheckedResolver {
    /// As USD's default resolver: anchored to the layer that names it; a
    /// search path not found there is looked for in the search paths.
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ar::ResolvedPath>) -> String {
        let anchored = self.inner.create_identifier(asset_path, anchor);
        if !self.search_paths.is_empty() && is_search_path(asset_path) && self.inner.resolve(&anchored).is_none() {
            for directory in &self.search_paths {
                let candidate = directory.join(asset_path);
                if candidate.exists() {
                    return candidate.canonicalize().unwrap_or(candidate).to_string_lossy().into_owned();
                }
            }
        }
        anchored
    }

    fn resolve(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.inner.resolve(asset_path)
    }

    fn resolve_for_new_asset(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.inner.resolve_for_new_asset(asset_path)
    }

    fn open_asset(&self, resolved_path: &ar::ResolvedPath) -> std::io::Result<Box<dyn ar::Asset>> {
        let text = resolved_path.to_string_lossy();
        let file = match ar::split_package_relative_path_outer(&text) {
            Some((package, _)) => PathBuf::from(package),
            None => resolved_path.to_path_buf(),
        };
        Self::check_file(&file)?;
        self.inner.open_asset(resolved_path)
    }

    fn identity(&self) -> String {
        let searched: String = self.search_paths.iter().map(|p| format!("{p:?}")).collect();
        format!("{}{searched}", self.inner.identity())
    }
}

impl CheckedResolver {
    /// The resolver of a stage opened with `search_paths` (then
    /// `PXR_AR_DEFAULT_SEARCH_PATH`'s directories, `:`-separated).
    fn new(search_paths: &[PathBuf]) -> Self {
        let mut search_paths = search_paths.to_vec();
        if let Some(paths) = std::env::var_os("PXR_AR_DEFAULT_SEARCH_PATH") {
            search_paths.extend(std::env::split_paths(&paths).filter(|p| !p.as_os_str().is_empty()));
        }
        Self { inner: ar::DefaultResolver::new(), search_paths }
    }
}

impl Stage {
    /// Opens the stage whose root layer is `path`, loading every payload;
    /// assets not beside the layer naming them are looked for in
    /// `search_paths`. What composition could not find (a layer, a format
    /// this reader does not read) is in [`Self::composition_errors`].
    pub(super) fn open(path: &Path, search_paths: &[PathBuf]) -> Result<Self, Failure> {
        let text = path.to_str().ok_or_else(|| "the path is not UTF-8".to_string())?;
        CheckedResolver::check_file(path).map_err(|e| e.to_string())?;
        let stage =
            usd::Stage::builder().resolver(CheckedResolver::new(search_paths)).open(text).map_err(|e| failure(&e))?;
        Ok(Self { stage, search_paths: search_paths.to_vec() })
    }

    /// The files of the layers read so far (the root, its sublayers, every
    /// referenced or payloaded layer; a package's member as the package).
    pub(super) fn layer_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = Vec::new();
        for identifier in self.stage.layer_identifiers() {
            let file = match ar::split_package_relative_path_outer(&identifier) {
                Some((package, _)) => PathBuf::from(package),
                None => PathBuf::from(&identifier),
            };
            if file.is_file() && !files.contains(&file) {
                files.push(file);
            }
        }
        files
    }

    /// Composition errors found since the stage was opened (a missing
    /// reference or payload surfaces as its prim is first read).
    ///
    /// One line per layer that could not be composed, naming the first
    /// prim that wanted it and how many more did, then one per other error.
    pub(super) fn composition_errors(&self) -> Vec<String> {
        use openusd::pcp::Error;
        let mut by_layer: Vec<(String, String, usize)> = Vec::new();
        let mut lines = Vec::new();
        for error in self.stage.composition_errors() {
            let (layer, line) = match &error {
                Error::UnresolvedLayer { asset_path, arc, site_path, .. } => (
                    asset_path.clone(),
                    format!("the {} layer '{asset_path}' cannot be found ({site_path}", arc_name(*arc)),
                ),
                Error::MalformedLayer { asset_path, arc, site_path, reason, .. } => {
                    let why = if reason.starts_with("no file format registered") {
                        let extension = Path::new(asset_path).extension().unwrap_or_default().to_string_lossy();
                        format!("is in a format this reader does not read (.{extension})")
                    } else {
                        format!("cannot be read: {reason}")
                    };
                    (asset_path.clone(), format!("the {} layer '{asset_path}' {why} ({site_path}", arc_name(*arc)))
                }
                _ => {
                    lines.push(composition_error(&error));
                    continue;
                }
            };
            match by_layer.iter_mut().find(|(l, _, _)| *l == layer) {
                Some(entry) => entry.2 += 1,
                None => by_layer.push((layer, line, 0)),
            }
        }
        let grouped = by_layer.into_iter().map(|(_, line, more)| match more {
            0 => format!("{line})"),
            n => format!("{line} and {n} more prims)"),
        });
        grouped.chain(lines).collect()
    }

    /// The layer metadata field `name` (`upAxis`, `metersPerUnit`...), as text
    /// or a number.
    pub(super) fn metadata_number(&self, name: &str) -> Result<Option<f64>, Failure> {
        let value = self.stage.stage_metadata(name).map_err(|e| failure(&e))?;
        Ok(value.and_then(|v| number(&v)))
    }

    pub(super) fn metadata_token(&self, name: &str) -> Result<Option<String>, Failure> {
        let value = self.stage.stage_metadata(name).map_err(|e| failure(&e))?;
        Ok(value.and_then(|v| text(&v)))
    }

    pub(super) fn default_prim(&self) -> Option<String> {
        self.stage.default_prim().map(|t| t.as_str().to_string())
    }

    /// The stage's start time code, when it authors a range.
    pub(super) fn start_time_code(&self) -> Option<f64> {
        self.stage.has_authored_time_code_range().then(|| self.stage.start_time_code())
    }

    /// The root prims' paths (children of `/`).
    pub(super) fn root_prims(&self) -> Result<Vec<String>, Failure> {
        let names = self.stage.root_prims().map_err(|e| failure(&e))?;
        Ok(names.iter().map(|n| format!("/{}", n.as_str())).collect())
    }

    /// The children's paths of `path`, in the stage's order.
    pub(super) fn children(&self, path: &str) -> Result<Vec<String>, Failure> {
        let prim = self.stage.prim(checked(path)?);
        let children = prim.children().map_err(|e| failure(&e))?;
        Ok(children.iter().map(|c| c.path().as_str().to_string()).collect())
    }

    pub(super) fn prim(&self, path: &str) -> Result<PrimInfo, Failure> {
        let prim = self.stage.prim(checked(path)?);
        let f = |e| failure(&e);
        let valid = prim.is_valid().map_err(f)?;
        if !valid {
            return Ok(PrimInfo::default());
        }
        let present =
            prim.is_active().map_err(f)? && prim.is_defined().map_err(f)? && !prim.is_abstract().map_err(f)?;
        let type_name = prim.type_name().map_err(f)?.map_or_else(String::new, |t| t.as_str().to_string());
        let api_schemas = prim.api_schemas().map_err(f)?.iter().map(|t| t.as_str().to_string()).collect();
        let prototype = if prim.is_instance().map_err(f)? {
            prim.prototype().map_err(f)?.map(|p| p.as_str().to_string())
        } else {
            None
        };
        Ok(PrimInfo { type_name, api_schemas, present, prototype })
    }

    /// The names of the prim's properties (attributes and relationships).
    pub(super) fn property_names(&self, path: &str) -> Result<Vec<String>, Failure> {
        let names = self.stage.prim(checked(path)?).property_names().map_err(|e| failure(&e))?;
        Ok(names.iter().map(|n| n.as_str().to_string()).collect())
    }

    /// The raw value of attribute `name` of `prim` at `time` (its default
    /// value when it has no time samples); None when nothing is authored.
    fn value(&self, prim: &str, name: &str, time: f64) -> Result<Option<sdf::Value>, Failure> {
        let attribute = self.stage.attribute(attribute_path(prim, name)?);
        let value: Option<sdf::Value> = attribute.get_at(usd::TimeCode::new(time)).map_err(|e| failure(&e))?;
        Ok(value.filter(|v| !matches!(v, sdf::Value::ValueBlock | sdf::Value::None)))
    }

    /// Whether attribute `name` of `prim` has an opinion (a value or samples).
    pub(super) fn has_value(&self, prim: &str, name: &str, time: f64) -> Result<bool, Failure> {
        Ok(self.value(prim, name, time)?.is_some())
    }

    /// Whether the attribute has more than one time sample.
    pub(super) fn varies(&self, prim: &str, name: &str) -> Result<bool, Failure> {
        let attribute = self.stage.attribute(attribute_path(prim, name)?);
        Ok(attribute.num_time_samples().map_err(|e| failure(&e))? > 1)
    }

    /// A scalar number (float, double, half or an integer).
    pub(super) fn number(&self, prim: &str, name: &str, time: f64) -> Result<Option<f64>, Failure> {
        self.typed(prim, name, time, "a number", |v| number(&v))
    }

    pub(super) fn boolean(&self, prim: &str, name: &str, time: f64) -> Result<Option<bool>, Failure> {
        self.typed(prim, name, time, "a bool", |v| match v {
            sdf::Value::Bool(b) => Some(b),
            sdf::Value::Int(i) => Some(i != 0),
            _ => None,
        })
    }

    /// A token or string.
    pub(super) fn token(&self, prim: &str, name: &str, time: f64) -> Result<Option<String>, Failure> {
        self.typed(prim, name, time, "a token or string", |v| text(&v))
    }

    /// An asset path, resolved as USD resolves it: against the layer that
    /// authored the value (a referenced layer's own folder, or the package
    /// holding it), not the root layer; where the file is absent, the
    /// place it was looked for.
    pub(super) fn asset(&self, prim: &str, name: &str, time: f64) -> Result<Option<Asset>, Failure> {
        let value = self.typed(prim, name, time, "an asset path", |v| match v {
            sdf::Value::AssetPath(a) => Some(a),
            sdf::Value::String(s) => Some(sdf::AssetPath::new(s)),
            _ => None,
        })?;
        let Some(value) = value else { return Ok(None) };
        let authored = value.asset_path().to_string();
        if authored.is_empty() {
            return Ok(Some(Asset { authored, location: String::new() }));
        }
        if let Some(resolved) = value.resolved_path() {
            return Ok(Some(Asset { authored, location: resolved.to_string() }));
        }
        // Not found: where it was looked for, anchored to the strongest
        // layer that authors the attribute.
        let attribute = self.stage.attribute(attribute_path(prim, name)?);
        let stack = attribute.property_stack().map_err(|e| failure(&e))?;
        let anchor = stack.first().map(|(layer, _)| ar::ResolvedPath::new(layer.as_str()));
        let resolver = CheckedResolver::new(&self.search_paths);
        let location = ar::Resolver::create_identifier(&resolver, &authored, anchor.as_ref());
        Ok(Some(Asset { authored, location }))
    }

    pub(super) fn vec2(&self, prim: &str, name: &str, time: f64) -> Result<Option<DVec2>, Failure> {
        self.typed(prim, name, time, "a 2-vector", |v| match v {
            sdf::Value::Vec2f(v) => Some(DVec2::new(f64::from(v.x), f64::from(v.y))),
            sdf::Value::Vec2d(v) => Some(DVec2::new(v.x, v.y)),
            sdf::Value::Vec2h(v) => Some(DVec2::new(f64::from(v.x), f64::from(v.y))),
            _ => None,
        })
    }

    pub(super) fn vec3(&self, prim: &str, name: &str, time: f64) -> Result<Option<DVec3>, Failure> {
        self.typed(prim, name, time, "a 3-vector", |v| vec3(&v))
    }

    pub(super) fn vec4(&self, prim: &str, name: &str, time: f64) -> Result<Option<DVec4>, Failure> {
        self.typed(prim, name, time, "a 4-vector", |v| match v {
            sdf::Value::Vec4f(v) => Some(DVec4::new(f64::from(v.x), f64::from(v.y), f64::from(v.z), f64::from(v.w))),
            sdf::Value::Vec4d(v) => Some(DVec4::new(v.x, v.y, v.z, v.w)),
            sdf::Value::Vec4h(v) => Some(DVec4::new(f64::from(v.x), f64::from(v.y), f64::from(v.z), f64::from(v.w))),
            _ => None,
        })
    }

    /// A quaternion (USD writes the real part first).
    pub(super) fn quat(&self, prim: &str, name: &str, time: f64) -> Result<Option<DQuat>, Failure> {
        self.typed(prim, name, time, "a quaternion", |v| match v {
            sdf::Value::Quatf(q) => Some(quat(q.w.into(), q.x.into(), q.y.into(), q.z.into())),
            sdf::Value::Quatd(q) => Some(quat(q.w, q.x, q.y, q.z)),
            sdf::Value::Quath(q) => Some(quat(q.w.into(), q.x.into(), q.y.into(), q.z.into())),
            _ => None,
        })
    }

    /// A 4 x 4 matrix as this crate uses them (columns, acting on column
    /// vectors): USD's matrices act on row vectors, so its rows are our
    /// columns and its translation row is our last column.
    pub(super) fn matrix(&self, prim: &str, name: &str, time: f64) -> Result<Option<DMat4>, Failure> {
        self.typed(prim, name, time, "a 4 x 4 matrix", |v| match v {
            sdf::Value::Matrix4d(m) => Some(DMat4::from_cols_array(&m.0)),
            _ => None,
        })
    }

    pub(super) fn ints(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<i64>>, Failure> {
        self.array(prim, name, time, "an int array", |v| match v {
            sdf::Value::IntVec(v) => Some(v.into_iter().map(i64::from).collect()),
            sdf::Value::Int64Vec(v) => Some(v),
            sdf::Value::UintVec(v) => Some(v.into_iter().map(i64::from).collect()),
            _ => None,
        })
    }

    /// An array of numbers (float, double or half).
    pub(super) fn numbers(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<f64>>, Failure> {
        self.array(prim, name, time, "a float array", |v| match v {
            sdf::Value::FloatVec(v) => Some(v.into_iter().map(f64::from).collect()),
            sdf::Value::DoubleVec(v) => Some(v),
            sdf::Value::HalfVec(v) => Some(v.into_iter().map(f64::from).collect()),
            _ => None,
        })
    }

    pub(super) fn vec2s(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<DVec2>>, Failure> {
        self.array(prim, name, time, "an array of 2-vectors", |v| match v {
            sdf::Value::Vec2fVec(v) => Some(v.iter().map(|v| DVec2::new(v.x.into(), v.y.into())).collect()),
            sdf::Value::Vec2dVec(v) => Some(v.iter().map(|v| DVec2::new(v.x, v.y)).collect()),
            sdf::Value::Vec2hVec(v) => Some(v.iter().map(|v| DVec2::new(v.x.into(), v.y.into())).collect()),
            _ => None,
        })
    }

    pub(super) fn vec3s(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<DVec3>>, Failure> {
        self.array(prim, name, time, "an array of 3-vectors", |v| match v {
            sdf::Value::Vec3fVec(v) => Some(v.iter().map(|v| DVec3::new(v.x.into(), v.y.into(), v.z.into())).collect()),
            sdf::Value::Vec3dVec(v) => Some(v.iter().map(|v| DVec3::new(v.x, v.y, v.z)).collect()),
            sdf::Value::Vec3hVec(v) => Some(v.iter().map(|v| DVec3::new(v.x.into(), v.y.into(), v.z.into())).collect()),
            _ => None,
        })
    }

    /// An array of colours for a primvar reader feeding a colour: 3-vectors
    /// as they are, 4-vectors' RGB, and numbers (float, double, half or
    /// int) as grey.
    pub(super) fn colours(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<DVec3>>, Failure> {
        let f = |x: f32| f64::from(x);
        self.array(prim, name, time, "an array of colours or numbers", |v| match v {
            sdf::Value::Vec3fVec(v) => Some(v.iter().map(|v| DVec3::new(f(v.x), f(v.y), f(v.z))).collect()),
            sdf::Value::Vec3dVec(v) => Some(v.iter().map(|v| DVec3::new(v.x, v.y, v.z)).collect()),
            sdf::Value::Vec3hVec(v) => Some(v.iter().map(|v| DVec3::new(v.x.into(), v.y.into(), v.z.into())).collect()),
            sdf::Value::Vec4fVec(v) => Some(v.iter().map(|v| DVec3::new(f(v.x), f(v.y), f(v.z))).collect()),
            sdf::Value::Vec4dVec(v) => Some(v.iter().map(|v| DVec3::new(v.x, v.y, v.z)).collect()),
            sdf::Value::FloatVec(v) => Some(v.into_iter().map(|x| DVec3::splat(f(x))).collect()),
            sdf::Value::DoubleVec(v) => Some(v.into_iter().map(DVec3::splat).collect()),
            sdf::Value::HalfVec(v) => Some(v.into_iter().map(|x| DVec3::splat(x.into())).collect()),
            sdf::Value::IntVec(v) => Some(v.into_iter().map(|x| DVec3::splat(f64::from(x))).collect()),
            _ => None,
        })
    }

    pub(super) fn quats(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<DQuat>>, Failure> {
        self.array(prim, name, time, "an array of quaternions", |v| match v {
            sdf::Value::QuathVec(v) => {
                Some(v.iter().map(|q| quat(q.w.into(), q.x.into(), q.y.into(), q.z.into())).collect())
            }
            sdf::Value::QuatfVec(v) => {
                Some(v.iter().map(|q| quat(q.w.into(), q.x.into(), q.y.into(), q.z.into())).collect())
            }
            sdf::Value::QuatdVec(v) => Some(v.iter().map(|q| quat(q.w, q.x, q.y, q.z)).collect()),
            _ => None,
        })
    }

    pub(super) fn tokens(&self, prim: &str, name: &str, time: f64) -> Result<Option<Vec<String>>, Failure> {
        self.array(prim, name, time, "a token array", |v| match v {
            sdf::Value::TokenVec(v) => Some(v.iter().map(|t| t.as_str().to_string()).collect()),
            sdf::Value::StringVec(v) => Some(v),
            _ => None,
        })
    }

    /// The attribute's `interpolation` metadata (a primvar's).
    pub(super) fn interpolation(&self, prim: &str, name: &str) -> Result<Option<String>, Failure> {
        let attribute = self.stage.attribute(attribute_path(prim, name)?);
        let value: Option<sdf::Value> = attribute.get_metadata("interpolation").map_err(|e| failure(&e))?;
        Ok(value.and_then(|v| text(&v)))
    }

    /// The targets of relationship `name` of `prim` (paths).
    pub(super) fn targets(&self, prim: &str, name: &str) -> Result<Vec<String>, Failure> {
        let relationship = self.stage.relationship(attribute_path(prim, name)?);
        let targets = relationship.targets().map_err(|e| failure(&e))?;
        Ok(targets.iter().map(|p| p.as_str().to_string()).collect())
    }

    /// The sources attribute `name` of `prim` is connected to
    /// (`/Material/Shader.outputs:rgb`).
    pub(super) fn connections(&self, prim: &str, name: &str) -> Result<Vec<String>, Failure> {
        let attribute = self.stage.attribute(attribute_path(prim, name)?);
        let sources = attribute.connections().map_err(|e| failure(&e))?;
        Ok(sources.iter().map(|p| p.as_str().to_string()).collect())
    }

    /// Whether `asset` is there to be read (a file, or a member of a package).
    pub(super) fn asset_exists(&self, asset: &Asset) -> bool {
        let location = asset.location.as_str();
        if ar::split_package_relative_path_outer(location).is_some() {
            let resolver = CheckedResolver::new(&self.search_paths);
            return ar::Resolver::resolve(&resolver, location).is_some();
        }
        Path::new(location).is_file()
    }

    /// The bytes of `asset` (at most `limit`), and the file they are in
    /// (the package, for a member of one: for messages and the scene's inputs).
    pub(super) fn asset_bytes(&self, asset: &Asset, limit: u64) -> Result<(PathBuf, Vec<u8>), Failure> {
        let location = asset.location.as_str();
        let not_found = || format!("cannot find '{}' (looked for {location})", asset.authored);
        if let Some((package, _)) = ar::split_package_relative_path_outer(location) {
            let resolver = CheckedResolver::new(&self.search_paths);
            let resolved = ar::Resolver::resolve(&resolver, location).ok_or_else(not_found)?;
            let mut reader = ar::Resolver::open_asset(&resolver, &resolved).map_err(|e| e.to_string())?;
            let mut bytes = Vec::new();
            reader.by_ref().take(limit + 1).read_to_end(&mut bytes).map_err(|e| e.to_string())?;
            if bytes.len() as u64 > limit {
                return Err(format!("'{}' is larger than {limit} bytes", asset.authored));
            }
            return Ok((PathBuf::from(package), bytes));
        }
        let file = PathBuf::from(location);
        if !file.exists() {
            return Err(not_found());
        }
        let bytes = crate::util::file::read_regular(&file, limit)
            .map_err(|e| format!("cannot read '{}': {e}", file.display()))?;
        Ok((file, bytes))
    }

    fn typed<T>(
        &self,
        prim: &str,
        name: &str,
        time: f64,
        expected: &str,
        convert: impl FnOnce(sdf::Value) -> Option<T>,
    ) -> Result<Option<T>, Failure> {
        match self.value(prim, name, time)? {
            None => Ok(None),
            Some(value) => {
                let kind = format!("{value:?}");
                let kind: String = kind.chars().take_while(|c| c.is_alphanumeric()).collect();
                convert(value).map(Some).ok_or_else(|| format!("must be {expected}, got a {kind}"))
            }
        }
    }

    fn array<T>(
        &self,
        prim: &str,
        name: &str,
        time: f64,
        expected: &str,
        convert: impl FnOnce(sdf::Value) -> Option<Vec<T>>,
    ) -> Result<Option<Vec<T>>, Failure> {
        let values = self.typed(prim, name, time, expected, convert)?;
        if values.as_ref().is_some_and(|v| v.len() > MAX_ARRAY) {
            return Err(format!("holds more than {MAX_ARRAY} elements"));
        }
        Ok(values)
    }
}

/// A composition error as text. The reader reports a chain of arcs nested
/// past USD's limit (100, C++ `MAX_COMPOSITION_DEPTH`) as a cycle: such a
/// chain, whose sites never repeat, is called what it is.
fn composition_error(error: &openusd::pcp::Error) -> String {
    if let openusd::pcp::Error::ArcCycle(chain) = error {
        let sites: std::collections::HashSet<(&str, String)> =
            chain.hops.iter().map(|hop| (hop.layer.as_str(), hop.path.as_str().to_string())).collect();
        // The root's own site counts as the first level.
        if sites.len() == chain.hops.len() && chain.hops.len() + 1 >= COMPOSITION_DEPTH {
            return format!(
                "{} is composed through a chain of {} nested references or payloads, no cycle, but deeper than \
                 USD's limit of {COMPOSITION_DEPTH} levels",
                chain.composing,
                chain.hops.len()
            );
        }
    }
    error.to_string()
}

/// An arc's kind as USD's documents name it.
fn arc_name(arc: openusd::pcp::ArcType) -> String {
    format!("{arc:?}").to_lowercase()
}

/// How deep USD nests composition arcs (C++ `MAX_COMPOSITION_DEPTH`).
const COMPOSITION_DEPTH: usize = 100;

fn number(value: &sdf::Value) -> Option<f64> {
    Some(match *value {
        sdf::Value::Float(x) => f64::from(x),
        sdf::Value::Double(x) => x,
        sdf::Value::Half(x) => f64::from(x),
        sdf::Value::Int(x) => f64::from(x),
        sdf::Value::Int64(x) => x as f64,
        sdf::Value::Uint(x) => f64::from(x),
        sdf::Value::Uchar(x) => f64::from(x),
        sdf::Value::TimeCode(t) => t.value(),
        _ => return None,
    })
}

fn text(value: &sdf::Value) -> Option<String> {
    match value {
        sdf::Value::Token(t) => Some(t.as_str().to_string()),
        sdf::Value::String(s) => Some(s.clone()),
        _ => None,
    }
}

fn vec3(value: &sdf::Value) -> Option<DVec3> {
    match value {
        sdf::Value::Vec3f(v) => Some(DVec3::new(v.x.into(), v.y.into(), v.z.into())),
        sdf::Value::Vec3d(v) => Some(DVec3::new(v.x, v.y, v.z)),
        sdf::Value::Vec3h(v) => Some(DVec3::new(v.x.into(), v.y.into(), v.z.into())),
        _ => None,
    }
}

fn quat(w: f64, x: f64, y: f64, z: f64) -> DQuat {
    DQuat::from_xyzw(x, y, z, w)
}
