//! The names of the frame's images, typed. Each pass output is an [`Output`] declared once, as a
//! `pub const` in the module of the pass that writes it; the pass's own declaration, the passes
//! that read it, history, capture, the viewer and the tests all use that constant, so a renamed
//! or removed output fails to compile. Names become text only where a person reads or types
//! them: capture files, the manifest, the viewer's list (`Resource`'s `Display`, and
//! [`super::Graph::resource_named`] for the way back).

use crate::gpu::vk;
use std::fmt;

/// One output of a pass: `taa.color` is `Output::new("taa", "color")`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Output {
    /// The pass that writes it (for a pass that runs several times a frame, its stage name).
    pub pass: &'static str,
    /// The output's name within the pass; also the GLSL binding's name (`out_color`, `in_color`).
    pub name: &'static str,
    /// Which run of a pass that runs several times a frame wrote it.
    pub instance: Instance,
}

/// One run of a pass that runs several times a frame (the SVGF stages: one chain per signal,
/// one a-trous stage per iteration); it becomes part of the pass's name
/// (`svgf_atrous` + `diffuse` + 0 = `svgf_atrous_diffuse_0`). Empty for every other pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Instance {
    pub signal: Option<&'static str>,
    pub iteration: Option<u32>,
}

impl Output {
    pub const fn new(pass: &'static str, name: &'static str) -> Self {
        Self { pass, name, instance: Instance { signal: None, iteration: None } }
    }

    /// The same output of run `instance` of its pass.
    pub const fn of(self, instance: Instance) -> Self {
        Self { instance, ..self }
    }

    /// The name of the pass run that writes it (`svgf_atrous_diffuse_0`).
    pub fn pass_name(&self) -> String {
        let mut s = self.pass.to_string();
        if let Some(signal) = self.instance.signal {
            s += &format!("_{signal}");
        }
        if let Some(i) = self.instance.iteration {
            s += &format!("_{i}");
        }
        s
    }
}

impl fmt::Display for Output {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}.{}", self.pass_name(), self.name)
    }
}

/// An image of the frame graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resource {
    /// Written by a pass this frame.
    Output(Output),
    /// The previous frame's copy of an output (`history.taa_color`), written by the history pass.
    History(Output),
    /// Zero everywhere and written by no pass: a stand-in a pass may read where the frame plan
    /// left out the pass that would have made the real input (for example the soft-shadow
    /// statistics when every light is punctual). `small` makes it 1x1.
    Zero { format: vk::Format, small: bool },
}

impl From<Output> for Resource {
    fn from(o: Output) -> Self {
        Resource::Output(o)
    }
}

impl fmt::Display for Resource {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Resource::Output(o) => o.fmt(f),
            Resource::History(o) => write!(f, "history.{}", o.to_string().replace('.', "_")),
            Resource::Zero { format, small } => {
                write!(f, "zero.{}{}", format.as_raw(), if *small { ".1x1" } else { "" })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_as_before() {
        const COLOR: Output = Output::new("svgf_atrous", "color");
        let run = COLOR.of(Instance { signal: Some("diffuse"), iteration: Some(2) });
        assert_eq!(run.to_string(), "svgf_atrous_diffuse_2.color");
        assert_eq!(Resource::History(run).to_string(), "history.svgf_atrous_diffuse_2_color");
        assert_eq!(Resource::from(Output::new("taa", "color")).to_string(), "taa.color");
        let zero = Resource::Zero { format: vk::Format::R32_UINT, small: true };
        assert_eq!(zero.to_string(), format!("zero.{}.1x1", vk::Format::R32_UINT.as_raw()));
    }
}
