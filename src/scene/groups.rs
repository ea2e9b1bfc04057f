//! Light groups, as Cycles has them: every light source, emitter, the sun
//! and the environment may name a group; the renderer writes each group's
//! light (direct, and the indirect light of the VPLs its paths leave) in a
//! layer of its own. A scene that names no group has one group and writes
//! no group layer.

use std::path::Path;

use super::file::GroupRule;
use super::SceneError;

/// The group of every light that names none.
pub const DEFAULT_GROUP: &str = "default";

/// Most groups a scene may have: a light tree per group and light kind, and
/// the cut numbers its trees in 9 bits (6 kinds x 63 groups = 378 < 512:
/// `light_tree::MAX_TREES`).
pub const MAX_LIGHT_GROUPS: usize = 63;

/// Most characters in a group name.
const MAX_NAME: usize = 64;

/// The scene's light groups and each light source's group.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LightGroups {
    /// Group names in the order of first use; empty when the scene names
    /// no group (then every light is in the one group 0).
    pub names: Vec<String>,
    /// The group of each of `Scene::lights`, by index into `names`.
    pub of_light: Vec<usize>,
    /// The group of the environment.
    pub environment: usize,
}

impl LightGroups {
    /// Groups from what each light asks for: `lights[i]` is the group light
    /// source i names (None: `default`) and the field that names it, for
    /// messages; `environment` likewise.
    pub fn assign(
        file: &Path,
        lights: &[(Option<String>, String)],
        environment: Option<(Option<String>, String)>,
    ) -> Result<Self, SceneError> {
        let all: Vec<&(Option<String>, String)> = lights.iter().chain(environment.as_ref()).collect();
        if all.iter().all(|(group, _)| group.is_none()) {
            return Ok(Self { names: Vec::new(), of_light: vec![0; lights.len()], environment: 0 });
        }
        let mut names: Vec<String> = Vec::new();
        let mut index = |group: &Option<String>, field: &str| -> Result<usize, SceneError> {
            let name = group.as_deref().unwrap_or(DEFAULT_GROUP);
            check_name(file, name, field)?;
            if let Some(i) = names.iter().position(|n| n == name) {
                return Ok(i);
            }
            if names.len() == MAX_LIGHT_GROUPS {
                return Err(SceneError::new(file, field, format!("more than {MAX_LIGHT_GROUPS} light groups")));
            }
            names.push(name.to_string());
            Ok(names.len() - 1)
        };
        let of_light = lights.iter().map(|(g, field)| index(g, field)).collect::<Result<Vec<_>, _>>()?;
        let environment = match &environment {
            Some((g, field)) => index(g, field)?,
            None => 0,
        };
        Ok(Self { names, of_light, environment })
    }

    /// Number of groups (1 when the scene names none).
    #[must_use]
    pub fn count(&self) -> usize {
        self.names.len().max(1)
    }

    /// Whether the scene names groups (and so gets group layers).
    #[must_use]
    pub fn named(&self) -> bool {
        !self.names.is_empty()
    }
}

/// A group name becomes part of an EXR channel name (`Combined_<group>.R`):
/// letters, digits, `_` and `-` only, so that no `.` splits the layer.
fn check_name(file: &Path, name: &str, field: &str) -> Result<(), SceneError> {
    let ok = !name.is_empty()
        && name.len() <= MAX_NAME
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(SceneError::new(
            file,
            field,
            format!("group '{name}' must be 1 to {MAX_NAME} letters, digits, '_' or '-' (it names an EXR layer)"),
        ))
    }
}

/// The names a glTF light is known by, for `[[gltf.groups]]` rules.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GltfLightNames {
    /// The KHR_lights_punctual light's name (punctual lights).
    pub light: Option<String>,
    /// The node that places it.
    pub node: Option<String>,
    /// The emissive material (mesh emitters).
    pub material: Option<String>,
}

/// Whether `name` matches `pattern`, where `*` matches any run of characters.
#[must_use]
pub fn matches(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !name.starts_with(first) || !name[first.len()..].ends_with(last) {
        return false;
    }
    let mut rest = &name[first.len()..name.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    true
}

/// The group each glTF light joins by the first rule that matches it (None:
/// no rule does). A rule that matches no light is an error: it is a typo or
/// a stale name, and the light it meant would silently stay in `default`.
pub fn apply_rules(
    file: &Path,
    rules: &[GroupRule],
    lights: &[GltfLightNames],
) -> Result<Vec<Option<String>>, SceneError> {
    let mut used = vec![false; rules.len()];
    for (i, rule) in rules.iter().enumerate() {
        let given = [&rule.light, &rule.node, &rule.material].iter().filter(|p| p.is_some()).count();
        if given != 1 {
            return Err(SceneError::new(
                file,
                format!("gltf.groups[{i}]"),
                "give exactly one of light, node or material".to_string(),
            ));
        }
        check_name(file, &rule.group, &format!("gltf.groups[{i}].group"))?;
    }
    let groups = lights
        .iter()
        .map(|names| {
            let hit = rules.iter().position(|rule| {
                let test = |pattern: &Option<String>, name: &Option<String>| match (pattern, name) {
                    (Some(p), Some(n)) => matches(p, n),
                    _ => false,
                };
                test(&rule.light, &names.light)
                    || test(&rule.node, &names.node)
                    || test(&rule.material, &names.material)
            });
            hit.map(|r| {
                used[r] = true;
                rules[r].group.clone()
            })
        })
        .collect();
    if let Some(unused) = used.iter().position(|u| !u) {
        let rule = &rules[unused];
        let (what, pattern) = match (&rule.light, &rule.node, &rule.material) {
            (Some(p), _, _) => ("light", p),
            (_, Some(p), _) => ("node", p),
            (_, _, Some(p)) => ("material", p),
            _ => unreachable!("checked above: exactly one is given"),
        };
        return Err(SceneError::new(
            file,
            format!("gltf.groups[{unused}].{what}"),
            format!("'{pattern}' matches no {what} of a light in the glTF file (or an earlier rule takes them all)"),
        ));
    }
    Ok(groups)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_match_runs_of_characters() {
        assert!(matches("Key", "Key"));
        assert!(!matches("Key", "Key.001"));
        assert!(matches("Key*", "Key.001"));
        assert!(matches("*light", "fill light"));
        assert!(matches("a*b*c", "a-xx-b-yy-c"));
        assert!(!matches("a*b*c", "a-xx-c-yy-b"));
        assert!(matches("*", ""));
        assert!(!matches("ab*ba", "aba"), "the two ends may not overlap");
    }

    #[test]
    fn groups_are_numbered_in_order_of_first_use_and_unnamed_lights_are_default() {
        let file = Path::new("g.toml");
        let l = |g: Option<&str>, i: usize| (g.map(str::to_string), format!("lights[{i}].group"));
        let groups = LightGroups::assign(
            file,
            &[l(Some("key"), 0), l(None, 1), l(Some("fill"), 2), l(Some("key"), 3)],
            Some((Some("sky".into()), "environment.group".into())),
        )
        .unwrap();
        assert_eq!(groups.names, ["key", "default", "fill", "sky"]);
        assert_eq!(groups.of_light, [0, 1, 2, 0]);
        assert_eq!(groups.environment, 3);
        assert!(groups.named());

        let none = LightGroups::assign(file, &[l(None, 0), l(None, 1)], Some((None, "environment".into()))).unwrap();
        assert!(!none.named());
        assert_eq!((none.count(), none.of_light.as_slice()), (1, [0, 0].as_slice()));
    }

    #[test]
    fn a_bad_group_name_is_an_error_naming_the_field() {
        let e = LightGroups::assign(Path::new("g.toml"), &[(Some("key.light".into()), "lights[2].group".into())], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("g.toml") && e.contains("lights[2].group") && e.contains("key.light"), "{e}");
    }

    #[test]
    fn gltf_rules_match_by_light_node_or_material_and_an_unused_rule_is_an_error() {
        let rule = |group: &str, light: Option<&str>, node: Option<&str>, material: Option<&str>| GroupRule {
            group: group.into(),
            light: light.map(Into::into),
            node: node.map(Into::into),
            material: material.map(Into::into),
        };
        let names = [
            GltfLightNames { light: Some("Key".into()), node: Some("KeyNode".into()), material: None },
            GltfLightNames { light: None, node: Some("Panel".into()), material: Some("Glow".into()) },
            GltfLightNames { light: Some("Other".into()), node: None, material: None },
        ];
        let file = Path::new("s.toml");
        let rules = [rule("key", Some("Key"), None, None), rule("fill", None, None, Some("Gl*"))];
        let groups = apply_rules(file, &rules, &names).unwrap();
        assert_eq!(groups, [Some("key".into()), Some("fill".into()), None]);

        let stale = [rule("key", None, Some("Nope"), None)];
        let e = apply_rules(file, &stale, &names).unwrap_err().to_string();
        assert!(e.contains("gltf.groups[0].node") && e.contains("Nope"), "{e}");
        let two = [rule("key", Some("Key"), Some("KeyNode"), None)];
        let e = apply_rules(file, &two, &names).unwrap_err().to_string();
        assert!(e.contains("gltf.groups[0]") && e.contains("exactly one"), "{e}");
    }
}
