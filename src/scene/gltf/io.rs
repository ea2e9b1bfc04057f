//! Reading a glTF file's bytes: the JSON (or GLB) parsed and validated,
//! buffers from the GLB's BIN chunk, base64 `data:` URIs or files, images
//! decoded, and accessors read into plain arrays with every offset, stride
//! and count checked against its buffer. Every error names the file and the
//! JSON location (`accessors[3].count`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Checked;

use super::IMPLEMENTED;
use crate::scene::image::{self, Encoding, RgbImage};
use crate::scene::SceneError;

/// Most vertices, indices or elements one accessor may hold (2^28): beyond
/// it a count is a corrupt file, not a scene.
const MAX_ACCESSOR_COUNT: usize = 1 << 28;

/// Parses and validates the JSON (or GLB), refusing required extensions the
/// renderer does not implement by name.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<gltf::Gltf, SceneError> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| {
        let location = match &e {
            gltf::Error::Binary(_) => "GLB container".to_string(),
            gltf::Error::Deserialize(d) => format!("line {}, column {}", d.line(), d.column()),
            _ => "file".to_string(),
        };
        SceneError::new(path, location, format!("not a readable glTF 2.0 file: {e}"))
    })?;
    for (i, name) in gltf.document.extensions_required().enumerate() {
        if !IMPLEMENTED.contains(&name) {
            return Err(SceneError::new(
                path,
                format!("extensionsRequired[{i}]"),
                format!(
                    "the file requires {name}, which this renderer does not implement (it implements {})",
                    IMPLEMENTED.join(", ")
                ),
            ));
        }
    }
    let mut root = gltf.document.clone().into_json();
    // gltf-json's validator refuses required extensions it does not model
    // itself, ours among them: we checked that list above.
    root.extensions_required.retain(|name| !IMPLEMENTED.contains(&name.as_str()));
    // gltf-json 1.4.1's validator indexes the POSITION accessor before
    // checking that it exists (a panic on a hostile file): check it first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&Checked::Valid(gltf::Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(SceneError::new(
                    path,
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    format!("accessor {} does not exist (the file has {})", index.value(), root.accessors.len()),
                ));
            }
        }
    }
    // gltf 1.4.1's Image::source unwraps `uri` when there is no buffer
    // view, and `mimeType` when there is (a panic on a hostile file): the
    // specification requires exactly one of uri and bufferView, and a
    // mimeType with a bufferView.
    for (i, image) in root.images.iter().enumerate() {
        let problem = match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => Some((String::new(), "has neither uri nor bufferView: one is required")),
            (Some(_), Some(_), _) => Some((String::new(), "has both uri and bufferView: give one")),
            (None, Some(_), None) => Some((".mimeType".into(), "missing: an image in a bufferView needs its mimeType")),
            _ => None,
        };
        if let Some((field, message)) = problem {
            return Err(SceneError::new(path, format!("images[{i}]{field}"), message));
        }
    }
    gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let (location, error) = &errors[0];
            let more = if errors.len() > 1 { format!(" (and {} more)", errors.len() - 1) } else { String::new() };
            SceneError::new(path, location.to_string(), format!("invalid: {error}{more}"))
        }
        other => SceneError::new(path, "file", other.to_string()),
    })?;
    Ok(gltf)
}

/// A glTF file's data: its buffers, the images decoded so far, and every
/// file read for them (in order).
pub(super) struct Data<'a> {
    file: &'a Path,
    /// The directory relative URIs resolve against.
    base: PathBuf,
    buffers: Vec<Vec<u8>>,
    /// Decoded images by glTF image index and encoding (linear RGB).
    images: HashMap<(usize, Encoding), std::rc::Rc<RgbImage>>,
    /// The buffer and image files read, in the order they were read.
    pub(super) inputs: Vec<PathBuf>,
}

impl<'a> Data<'a> {
    /// Reads every buffer of `doc`: the GLB's BIN chunk (`blob`), a base64
    /// `data:` URI or a file relative to `file`.
    pub(super) fn load(file: &'a Path, doc: &gltf::Document, blob: Option<&[u8]>) -> Result<Self, SceneError> {
        let mut data = Self {
            file,
            base: file.parent().unwrap_or(Path::new(".")).to_path_buf(),
            buffers: Vec::new(),
            images: HashMap::new(),
            inputs: Vec::new(),
        };
        data.load_buffers(doc, blob)?;
        Ok(data)
    }

    fn error(&self, location: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, location, message)
    }

    /// Reads every buffer: the GLB's BIN chunk, a base64 `data:` URI or a file.
    fn load_buffers(&mut self, doc: &gltf::Document, blob: Option<&[u8]>) -> Result<(), SceneError> {
        for buffer in doc.buffers() {
            let location = format!("buffers[{}]", buffer.index());
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .ok_or_else(|| {
                        self.error(&location, "refers to the GLB's BIN chunk, which the file does not have")
                    })?
                    .to_vec(),
                // No more of a file than the buffer declares it holds.
                gltf::buffer::Source::Uri(uri) => {
                    self.read_uri(uri, &format!("{location}.uri"), Some(buffer.length() as u64))?
                }
            };
            if data.len() < buffer.length() {
                return Err(self.error(
                    format!("{location}.byteLength"),
                    format!("is {} but the data holds only {} bytes", buffer.length(), data.len()),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes a URI names: a base64 `data:` URI, or a regular file
    /// relative to the glTF file (its first `declared` bytes, when a buffer
    /// declares its length; else the whole file, up to
    /// [`MAX_FILE_BYTES`](crate::util::file::MAX_FILE_BYTES)).
    fn read_uri(&mut self, uri: &str, location: &str, declared: Option<u64>) -> Result<Vec<u8>, SceneError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((_, payload)) = rest.split_once(";base64,") else {
                return Err(self.error(location, "a data: URI must be base64 (';base64,')"));
            };
            return base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| self.error(location, format!("bad base64 data: {e}")));
        }
        if let Some((scheme, _)) = uri.split_once("://") {
            return Err(
                self.error(location, format!("'{scheme}://' URIs are not supported: give a relative file path"))
            );
        }
        let path = self.base.join(percent_decode(uri));
        let read = match declared {
            Some(length) if length <= crate::util::file::MAX_FILE_BYTES => {
                crate::util::file::read_regular_prefix(&path, length)
            }
            Some(length) => {
                return Err(self.error(
                    location.replace(".uri", ".byteLength"),
                    format!("is {length}, more than {} bytes", crate::util::file::MAX_FILE_BYTES),
                ))
            }
            None => crate::util::file::read_regular(&path, crate::util::file::MAX_FILE_BYTES),
        };
        let bytes = read.map_err(|e| self.error(location, format!("cannot read '{}': {e}", path.display())))?;
        self.inputs.push(path);
        Ok(bytes)
    }

    /// Decodes an image (glTF's PNG or JPEG, or any format
    /// [`image::decode_named`] reads; its colours encoded as `encoding`
    /// says) once.
    pub(super) fn image(
        &mut self,
        image: &gltf::Image<'_>,
        location: &str,
        encoding: Encoding,
    ) -> Result<std::rc::Rc<RgbImage>, SceneError> {
        if let Some(decoded) = self.images.get(&(image.index(), encoding)) {
            return Ok(std::rc::Rc::clone(decoded));
        }
        let at = format!("images[{}]", image.index());
        let (bytes, named) = match image.source() {
            gltf::image::Source::Uri { uri, .. } => {
                let bytes = self.read_uri(uri, &format!("{at}.uri"), None)?;
                let named = if uri.starts_with("data:") { None } else { Some(self.base.join(percent_decode(uri))) };
                (bytes, named)
            }
            gltf::image::Source::View { view, .. } => {
                (self.view_bytes(&view, &format!("{at}.bufferView"))?.to_vec(), None)
            }
        };
        let name = named.as_ref().map_or_else(String::new, |p| p.to_string_lossy().into_owned());
        let decoded = image::decode_named(&bytes, &name, encoding).map_err(|e| {
            let what = named.as_ref().map_or_else(String::new, |p| format!("'{}': ", p.display()));
            self.error(format!("{location} ({at})"), format!("{what}{e}"))
        })?;
        // Shared, not copied: a 4096 x 4096 image is 200 MB of f32 texels.
        let decoded = std::rc::Rc::new(decoded);
        self.images.insert((image.index(), encoding), std::rc::Rc::clone(&decoded));
        Ok(decoded)
    }

    /// The bytes of a buffer view, checked against its buffer.
    pub(super) fn view_bytes(&self, view: &gltf::buffer::View<'_>, location: &str) -> Result<&[u8], SceneError> {
        let buffer = &self.buffers[view.buffer().index()];
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= buffer.len() => Ok(&buffer[view.offset()..end]),
            _ => Err(self.error(
                format!("bufferViews[{}]", view.index()),
                format!(
                    "bytes {}..{} are past the end of buffers[{}] ({} bytes) ({location})",
                    view.offset(),
                    view.offset().saturating_add(view.length()),
                    view.buffer().index(),
                    buffer.len()
                ),
            )),
        }
    }

    /// An accessor's dense elements, as bytes from its first element and
    /// the stride between elements; None when it has no buffer view (all
    /// zeros, before any sparse substitution).
    fn elements(
        &self,
        a: &gltf::Accessor<'_>,
        location: &str,
        size: usize,
    ) -> Result<Option<(&[u8], usize)>, SceneError> {
        let at = format!("accessors[{}]", a.index());
        if a.count() > MAX_ACCESSOR_COUNT {
            return Err(self.error(
                format!("{at}.count"),
                format!("{} is more than {MAX_ACCESSOR_COUNT} ({location})", a.count()),
            ));
        }
        let Some(view) = a.view() else { return Ok(None) };
        let bytes = self.view_bytes(&view, location)?;
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(self.error(
                format!("bufferViews[{}].byteStride", view.index()),
                format!("{stride} is less than an element's {size} bytes ({location})"),
            ));
        }
        let needed = match a.count() {
            0 => Some(0),
            n => (n - 1).checked_mul(stride).and_then(|x| x.checked_add(size)).and_then(|x| x.checked_add(a.offset())),
        };
        match needed {
            Some(n) if n <= bytes.len() => Ok(Some((&bytes[a.offset().min(bytes.len())..], stride))),
            _ => Err(self.error(
                at.to_string(),
                format!("{} elements of {size} bytes every {stride} from byte {} overrun bufferViews[{}] ({} bytes) ({location})", a.count(), a.offset(), view.index(), bytes.len()),
            )),
        }
    }

    /// An accessor's `count` elements of `size` bytes, each read by `read`:
    /// the dense ones (zeros without a buffer view), then the sparse
    /// substitution the specification defines (section 3.6.2.3: `sparse.count`
    /// strictly increasing indices, each element at one replaced by the
    /// next tightly packed value).
    fn read_elements<T: Clone>(
        &self,
        a: &gltf::Accessor<'_>,
        location: &str,
        (size, zero): (usize, T),
        read: impl Fn(&[u8]) -> T,
    ) -> Result<Vec<T>, SceneError> {
        let mut out = match self.elements(a, location, size)? {
            None => vec![zero; a.count()],
            Some((bytes, stride)) => (0..a.count()).map(|i| read(&bytes[i * stride..])).collect(),
        };
        let Some(sparse) = a.sparse() else { return Ok(out) };
        let at = format!("accessors[{}].sparse", a.index());
        let n = sparse.count();
        if n == 0 || n > a.count() {
            return Err(self.error(
                format!("{at}.count"),
                format!("{n} must be between 1 and the accessor's count {} ({location})", a.count()),
            ));
        }
        let index_size = match sparse.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let packed = |view: gltf::buffer::View<'_>, offset: usize, each: usize, field: &str| {
            let bytes = self.view_bytes(&view, location)?;
            match n.checked_mul(each).and_then(|x| x.checked_add(offset)) {
                Some(end) if end <= bytes.len() => Ok(&bytes[offset..end]),
                _ => Err(self.error(
                    format!("{at}.{field}"),
                    format!("{n} elements of {each} bytes from byte {offset} overrun bufferViews[{}] ({} bytes) ({location})", view.index(), bytes.len()),
                )),
            }
        };
        let indices = sparse.indices();
        let index_bytes = packed(indices.view(), indices.offset(), index_size, "indices")?;
        let values = sparse.values();
        let value_bytes = packed(values.view(), values.offset(), size, "values")?;
        let mut previous = None;
        for k in 0..n {
            let b = &index_bytes[k * index_size..];
            let index = match index_size {
                1 => usize::from(b[0]),
                2 => usize::from(u16::from_le_bytes([b[0], b[1]])),
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if index >= a.count() || previous.is_some_and(|p| index <= p) {
                return Err(self.error(
                    format!("{at}.indices"),
                    format!(
                        "index {k} is {index}: sparse indices must strictly increase and stay below the accessor's count {} ({location})",
                        a.count()
                    ),
                ));
            }
            previous = Some(index);
            out[index] = read(&value_bytes[k * size..]);
        }
        Ok(out)
    }

    /// A float accessor of N components (2, 3, 4 or 16 for a MAT4): FLOAT,
    /// normalized integers, or (KHR_mesh_quantization) integers read as
    /// their values.
    pub(super) fn read_floats<const N: usize>(
        &self,
        a: &gltf::Accessor<'_>,
        location: &str,
    ) -> Result<Vec<[f32; N]>, SceneError> {
        let want = match N {
            1 => Dimensions::Scalar,
            2 => Dimensions::Vec2,
            3 => Dimensions::Vec3,
            16 => Dimensions::Mat4,
            _ => Dimensions::Vec4,
        };
        if a.dimensions() != want {
            return Err(self.error(location, format!("must be a {want:?} accessor, got {:?}", a.dimensions())));
        }
        let kind = a.data_type();
        let normalized = a.normalized();
        if kind == DataType::F32 && normalized {
            return Err(self.error(location, "a FLOAT accessor cannot be normalized"));
        }
        let component = kind.size();
        // The specification's decoding of normalized integers (section 3.11).
        let read = move |b: &[u8]| -> f32 {
            match (kind, normalized) {
                (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                (DataType::U8, true) => f32::from(b[0]) / 255.0,
                (DataType::I8, true) => (f32::from(b[0] as i8) / 127.0).max(-1.0),
                (DataType::U16, true) => f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
                (DataType::I16, true) => (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0),
                (DataType::U32, true) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32 / u32::MAX as f32,
                (DataType::U8, false) => f32::from(b[0]),
                (DataType::I8, false) => f32::from(b[0] as i8),
                (DataType::U16, false) => f32::from(u16::from_le_bytes([b[0], b[1]])),
                (DataType::I16, false) => f32::from(i16::from_le_bytes([b[0], b[1]])),
                (DataType::U32, false) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            }
        };
        // Column-major; a MAT4's columns need no padding (section 3.6.2.4).
        self.read_elements(a, location, (N * component, [0.0; N]), |b| {
            std::array::from_fn(|c| read(&b[c * component..]))
        })
    }

    /// An index accessor (unsigned byte, short or int scalars).
    pub(super) fn read_indices(&self, a: &gltf::Accessor<'_>, location: &str) -> Result<Vec<u32>, SceneError> {
        let kind = a.data_type();
        if a.dimensions() != Dimensions::Scalar || !matches!(kind, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(
                self.error(location, format!("indices must be unsigned scalars, got {:?} {kind:?}", a.dimensions()))
            );
        }
        self.read_elements(a, location, (kind.size(), 0), |b| match kind {
            DataType::U8 => u32::from(b[0]),
            DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        })
    }
}

/// `%20`-style escapes of a relative URI decoded (invalid escapes kept).
pub(super) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
