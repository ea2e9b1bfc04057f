//! The schemas' fallback values, in one table: what an attribute means
//! when a stage authors nothing for it. `openusd` 0.6 has no schema
//! registry and answers "nothing" for an unauthored attribute, so every
//! default the import relies on is written here, copied from the schemas
//! as Pixar's usd-core 26 ships them (`usdGeom`, `usdLux` and
//! `usdShaders`' generated schemas). docs/scene-format.md, "USD".

use glam::{DVec2, DVec3, DVec4};

use super::stage::{Failure, Stage};

/// A fallback value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Fallback {
    Number(f64),
    Bool(bool),
    Token(&'static str),
    Vec2([f64; 2]),
    Vec3([f64; 3]),
    Vec4([f64; 4]),
}

/// (schema, attribute, fallback); the schema `*` stands for an applied API
/// schema's or a base class's attribute, which every prim type shares
/// unless a row for its own type overrides it (DistantLight's intensity).
const FALLBACKS: &[(&str, &str, Fallback)] = {
    use Fallback::{Bool, Number, Token, Vec2, Vec3, Vec4};
    &[
        // UsdGeomImageable, UsdGeomGprim, UsdGeomMesh.
        ("*", "visibility", Token("inherited")),
        ("*", "purpose", Token("default")),
        ("*", "doubleSided", Bool(false)),
        ("*", "orientation", Token("rightHanded")),
        ("Mesh", "subdivisionScheme", Token("catmullClark")),
        ("Mesh", "interpolateBoundary", Token("edgeAndCorner")),
        ("Mesh", "faceVaryingLinearInterpolation", Token("cornersPlus1")),
        // The intrinsic gprims.
        ("Sphere", "radius", Number(1.0)),
        ("Cube", "size", Number(2.0)),
        ("Cylinder", "radius", Number(1.0)),
        ("Cylinder", "height", Number(2.0)),
        ("Cylinder", "axis", Token("Z")),
        ("Cone", "radius", Number(1.0)),
        ("Cone", "height", Number(2.0)),
        ("Cone", "axis", Token("Z")),
        ("Capsule", "radius", Number(0.5)),
        ("Capsule", "height", Number(1.0)),
        ("Capsule", "axis", Token("Z")),
        ("Plane", "width", Number(2.0)),
        ("Plane", "length", Number(2.0)),
        ("Plane", "axis", Token("Z")),
        // UsdGeomCamera: focal length and apertures in tenths of a scene unit.
        ("Camera", "projection", Token("perspective")),
        ("Camera", "focalLength", Number(50.0)),
        ("Camera", "horizontalAperture", Number(20.955)),
        ("Camera", "verticalAperture", Number(15.2908)),
        ("Camera", "horizontalApertureOffset", Number(0.0)),
        ("Camera", "verticalApertureOffset", Number(0.0)),
        ("Camera", "clippingRange", Vec2([1.0, 1_000_000.0])),
        ("Camera", "fStop", Number(0.0)),
        ("Camera", "focusDistance", Number(0.0)),
        // UsdLuxLightAPI, on every light.
        ("*", "inputs:intensity", Number(1.0)),
        ("DistantLight", "inputs:intensity", Number(50_000.0)),
        ("*", "inputs:exposure", Number(0.0)),
        ("*", "inputs:color", Vec3([1.0, 1.0, 1.0])),
        ("*", "inputs:normalize", Bool(false)),
        ("*", "inputs:enableColorTemperature", Bool(false)),
        ("*", "inputs:colorTemperature", Number(6500.0)),
        ("*", "inputs:diffuse", Number(1.0)),
        ("*", "inputs:specular", Number(1.0)),
        // The lights' shapes.
        ("DistantLight", "inputs:angle", Number(0.53)),
        ("RectLight", "inputs:width", Number(1.0)),
        ("RectLight", "inputs:height", Number(1.0)),
        ("DiskLight", "inputs:radius", Number(0.5)),
        ("SphereLight", "inputs:radius", Number(0.5)),
        ("SphereLight", "treatAsPoint", Bool(false)),
        ("CylinderLight", "inputs:radius", Number(0.5)),
        ("CylinderLight", "inputs:length", Number(1.0)),
        ("CylinderLight", "treatAsLine", Bool(false)),
        ("DomeLight", "inputs:texture:format", Token("automatic")),
        ("DomeLight_1", "inputs:texture:format", Token("automatic")),
        ("DomeLight_1", "poleAxis", Token("scene")),
        // UsdLuxShapingAPI.
        ("*", "inputs:shaping:cone:angle", Number(90.0)),
        ("*", "inputs:shaping:cone:softness", Number(0.0)),
        ("*", "inputs:shaping:focus", Number(0.0)),
        // UsdPreviewSurface.
        ("UsdPreviewSurface", "inputs:diffuseColor", Vec3([0.18, 0.18, 0.18])),
        ("UsdPreviewSurface", "inputs:emissiveColor", Vec3([0.0, 0.0, 0.0])),
        ("UsdPreviewSurface", "inputs:useSpecularWorkflow", Number(0.0)),
        ("UsdPreviewSurface", "inputs:specularColor", Vec3([0.0, 0.0, 0.0])),
        ("UsdPreviewSurface", "inputs:metallic", Number(0.0)),
        ("UsdPreviewSurface", "inputs:roughness", Number(0.5)),
        ("UsdPreviewSurface", "inputs:clearcoat", Number(0.0)),
        ("UsdPreviewSurface", "inputs:clearcoatRoughness", Number(0.01)),
        ("UsdPreviewSurface", "inputs:opacity", Number(1.0)),
        ("UsdPreviewSurface", "inputs:opacityThreshold", Number(0.0)),
        ("UsdPreviewSurface", "inputs:ior", Number(1.5)),
        ("UsdPreviewSurface", "inputs:normal", Vec3([0.0, 0.0, 1.0])),
        ("UsdPreviewSurface", "inputs:displacement", Number(0.0)),
        ("UsdPreviewSurface", "inputs:occlusion", Number(1.0)),
        // UsdUVTexture.
        ("UsdUVTexture", "inputs:wrapS", Token("useMetadata")),
        ("UsdUVTexture", "inputs:wrapT", Token("useMetadata")),
        ("UsdUVTexture", "inputs:fallback", Vec4([0.0, 0.0, 0.0, 1.0])),
        ("UsdUVTexture", "inputs:scale", Vec4([1.0, 1.0, 1.0, 1.0])),
        ("UsdUVTexture", "inputs:bias", Vec4([0.0, 0.0, 0.0, 0.0])),
        ("UsdUVTexture", "inputs:sourceColorSpace", Token("auto")),
        // UsdTransform2d.
        ("UsdTransform2d", "inputs:rotation", Number(0.0)),
        ("UsdTransform2d", "inputs:scale", Vec2([1.0, 1.0])),
        ("UsdTransform2d", "inputs:translation", Vec2([0.0, 0.0])),
        // UsdPrimvarReader_float2.
        ("UsdPrimvarReader_float2", "inputs:varname", Token("")),
        ("UsdPrimvarReader_float2", "inputs:fallback", Vec2([0.0, 0.0])),
    ]
};

/// The fallback of `attribute` on a prim (or shader) of type `schema`.
pub(super) fn fallback(schema: &str, attribute: &str) -> Option<Fallback> {
    let own = FALLBACKS.iter().find(|(s, a, _)| *s == schema && *a == attribute);
    own.or_else(|| FALLBACKS.iter().find(|(s, a, _)| *s == "*" && *a == attribute)).map(|&(_, _, f)| f)
}

/// Reads a prim's attributes with their schema's fallbacks: what the
/// import reads a light, a camera, a gprim or a shader through. Every
/// read names the prim and attribute in its error.
pub(super) struct Reader<'s> {
    pub stage: &'s Stage,
    pub prim: &'s str,
    /// The schema whose fallbacks apply (the prim's type, or a shader's id).
    pub schema: &'s str,
    pub time: f64,
}

/// An attribute that is neither authored nor in the table: a bug of the
/// import (it asked for an attribute with no fallback), reported as the
/// stage's error all the same.
fn missing(attribute: &str) -> Failure {
    format!("{attribute}: not authored and without a schema fallback")
}

impl Reader<'_> {
    fn wrong(&self, attribute: &str, message: &str) -> (String, Failure) {
        (format!("{}.{attribute}", self.prim), message.to_string())
    }

    pub(super) fn number(&self, attribute: &str) -> Result<f64, (String, Failure)> {
        let authored = self.stage.number(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        let value = match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) => v,
            (None, Some(Fallback::Number(v))) => v,
            (None, Some(Fallback::Bool(b))) => f64::from(u8::from(b)),
            _ => return Err(self.wrong(attribute, &missing(attribute))),
        };
        if !value.is_finite() {
            return Err(self.wrong(attribute, &format!("must be finite, got {value}")));
        }
        Ok(value)
    }

    pub(super) fn boolean(&self, attribute: &str) -> Result<bool, (String, Failure)> {
        let authored = self.stage.boolean(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) | (None, Some(Fallback::Bool(v))) => Ok(v),
            _ => Err(self.wrong(attribute, &missing(attribute))),
        }
    }

    pub(super) fn token(&self, attribute: &str) -> Result<String, (String, Failure)> {
        let authored = self.stage.token(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) => Ok(v),
            (None, Some(Fallback::Token(t))) => Ok(t.to_string()),
            _ => Err(self.wrong(attribute, &missing(attribute))),
        }
    }

    pub(super) fn vec2(&self, attribute: &str) -> Result<DVec2, (String, Failure)> {
        let authored = self.stage.vec2(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        let value = match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) => v,
            (None, Some(Fallback::Vec2(v))) => DVec2::from(v),
            _ => return Err(self.wrong(attribute, &missing(attribute))),
        };
        self.finite(attribute, value.is_finite(), value)
    }

    pub(super) fn vec3(&self, attribute: &str) -> Result<DVec3, (String, Failure)> {
        let authored = self.stage.vec3(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        let value = match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) => v,
            (None, Some(Fallback::Vec3(v))) => DVec3::from(v),
            _ => return Err(self.wrong(attribute, &missing(attribute))),
        };
        self.finite(attribute, value.is_finite(), value)
    }

    pub(super) fn vec4(&self, attribute: &str) -> Result<DVec4, (String, Failure)> {
        let authored = self.stage.vec4(self.prim, attribute, self.time).map_err(|e| self.wrong(attribute, &e))?;
        let value = match (authored, fallback(self.schema, attribute)) {
            (Some(v), _) => v,
            (None, Some(Fallback::Vec4(v))) => DVec4::from(v),
            _ => return Err(self.wrong(attribute, &missing(attribute))),
        };
        self.finite(attribute, value.is_finite(), value)
    }

    fn finite<T: std::fmt::Debug>(&self, attribute: &str, finite: bool, value: T) -> Result<T, (String, Failure)> {
        if finite {
            Ok(value)
        } else {
            Err(self.wrong(attribute, &format!("must be finite, got {value:?}")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_type_s_own_fallback_wins_over_the_shared_one() {
        assert_eq!(fallback("DistantLight", "inputs:intensity"), Some(Fallback::Number(50_000.0)));
        assert_eq!(fallback("RectLight", "inputs:intensity"), Some(Fallback::Number(1.0)));
        assert_eq!(fallback("SphereLight", "inputs:radius"), Some(Fallback::Number(0.5)));
        assert_eq!(fallback("Sphere", "radius"), Some(Fallback::Number(1.0)));
        assert_eq!(fallback("Sphere", "inputs:radius"), None);
        assert_eq!(fallback("Mesh", "subdivisionScheme"), Some(Fallback::Token("catmullClark")));
    }
}
