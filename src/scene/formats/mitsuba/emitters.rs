//! Mitsuba emitters: point and directional lights, and the environment
//! (`constant`, `envmap`); area lights are read with their shapes.

use glam::Vec3;
use roxmltree::Node;

use super::Mitsuba;
use crate::environment::Environment;
use crate::scene::{Light, SceneError};

impl Mitsuba<'_> {
    pub(super) fn emitter(&mut self, node: Node) -> Result<(), SceneError> {
        let ty = self.attr(node, "type")?;
        let m = self.to_world(node)?;
        match ty.as_str() {
            "point" => {
                let position = match self.prop(node, "position") {
                    Some(p) => self.vec3(p, "value")?,
                    None => m.transform_point3(Vec3::ZERO),
                };
                self.lights.push(Light::Point {
                    position,
                    intensity: self.color(node, "intensity", Vec3::ONE)?,
                });
            }
            "directional" => {
                let direction = match self.prop(node, "direction") {
                    Some(p) => self.vec3(p, "value")?,
                    None => m.transform_vector3(Vec3::Z),
                };
                if direction.length_squared() == 0.0 {
                    return Err(self.err(node, "directional light with zero direction"));
                }
                self.lights.push(Light::Directional {
                    direction: direction.normalize(),
                    irradiance: self.color(node, "irradiance", Vec3::ONE)?,
                });
            }
            "constant" => {
                let l = self.color(node, "radiance", Vec3::ONE)?;
                let env = Environment::uniform(l).map_err(|e| self.err(node, e.to_string()))?;
                self.set_environment(node, env);
            }
            "envmap" => {
                let file = self
                    .prop(node, "filename")
                    .ok_or_else(|| self.err(node, "envmap without filename"))?;
                let p = self.dir.join(self.attr(file, "value")?);
                let scale = self.scalar_prop(node, "scale", 1.0)?;
                let map = super::super::common::read_lat_long(&p, scale)?;
                if node.children().any(|c| c.has_tag_name("transform")) {
                    self.warnings.push(format!(
                        "{}:{}: the envmap's to_world is not supported: the map is used unrotated (+Y up)",
                        self.path.display(),
                        self.line(node)
                    ));
                }
                self.set_environment(node, Environment::LatLong(map));
            }
            other => self.warnings.push(format!(
                "{}:{}: emitter {other:?} not supported, skipped",
                self.path.display(),
                self.line(node)
            )),
        }
        Ok(())
    }

    /// The scene's environment; a second one replaces the first, with a warning.
    fn set_environment(&mut self, node: Node, env: Environment) {
        if self.environment.is_some() {
            self.warnings.push(format!(
                "{}:{}: a second environment emitter replaces the first",
                self.path.display(),
                self.line(node)
            ));
        }
        self.environment = Some(env);
    }
}
