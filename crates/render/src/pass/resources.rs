//! What passes write and later passes read, by name ([`Resources`]): the registry a scene's
//! passes fill when it is uploaded. Each pass first allocates what it writes
//! ([`super::Pass::allocate`], in frame order), then prepares what it draws with from what the
//! registry holds ([`super::Pass::prepare`]), so a pass reads another's texture by the name both
//! give `--explain` ("shadow map", "tsd depth", ...) and no central type lists them. A group of
//! passes may also share state that is not on the GPU through it (TSD's culling).

use std::any::Any;

/// A scene's shared resources, each under the name its writer gives it.
#[derive(Default)]
pub(crate) struct Resources {
    entries: Vec<(&'static str, Box<dyn Any + Send + Sync>)>,
}

impl Resources {
    /// Registers `value` as `name` (a pass allocating what it writes). A second value under a
    /// name replaces the first.
    pub(crate) fn put<T: Any + Send + Sync>(&mut self, name: &'static str, value: T) {
        self.entries.retain(|(n, _)| *n != name);
        self.entries.push((name, Box::new(value)));
    }

    /// The resource `name`, when a pass registered one of type `T`.
    pub(crate) fn find<T: 'static>(&self, name: &str) -> Option<&T> {
        self.entries.iter().find(|(n, _)| *n == name).and_then(|(_, value)| value.downcast_ref::<T>())
    }

    /// The resource `name`, which the pass graph guarantees an earlier pass wrote.
    ///
    /// # Panics
    /// When no pass registered `name` as a `T`: a pass listed without the pass it reads from,
    /// which the pass list never makes (`tests/render/pass_graph.rs` walks every combination).
    pub(crate) fn get<T: 'static>(&self, name: &str) -> &T {
        self.find(name).unwrap_or_else(|| panic!("no pass wrote the resource {name:?} this pass reads"))
    }

    /// A view of the texture `name`, which the pass graph guarantees an earlier pass wrote.
    ///
    /// # Panics
    /// As [`Resources::get`].
    pub(crate) fn texture_view(&self, name: &str) -> wgpu::TextureView {
        self.get::<wgpu::Texture>(name).create_view(&Default::default())
    }

    /// A view of the texture `name`, when a pass registered it.
    pub(crate) fn view(&self, name: &str) -> Option<wgpu::TextureView> {
        self.find::<wgpu::Texture>(name).map(|t| t.create_view(&Default::default()))
    }

    /// The names registered, in the order they were.
    #[cfg(test)]
    pub(crate) fn names(&self) -> Vec<&'static str> {
        self.entries.iter().map(|(n, _)| *n).collect()
    }

    /// The names of the textures registered, in the order they were (the registry also holds
    /// what a group of passes shares that is not on the GPU, as TSD's culling state).
    pub(crate) fn texture_names(&self) -> Vec<&'static str> {
        self.entries.iter().filter(|(_, value)| value.is::<wgpu::Texture>()).map(|(n, _)| *n).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::Resources;

    #[test]
    fn a_resource_is_found_by_name_and_type_and_replaced_by_a_second_put() {
        let mut resources = Resources::default();
        resources.put("a", 1_u32);
        resources.put("b", "text");
        assert_eq!(resources.find::<u32>("a"), Some(&1));
        assert_eq!(resources.find::<u64>("a"), None, "another type is not found");
        assert_eq!(resources.find::<u32>("c"), None);
        resources.put("a", 2_u32);
        assert_eq!(*resources.get::<u32>("a"), 2);
        assert_eq!(resources.names(), ["b", "a"]);
    }

    #[test]
    #[should_panic(expected = "no pass wrote the resource \"shadow map\"")]
    fn reading_what_no_pass_wrote_names_it() {
        Resources::default().get::<u32>("shadow map");
    }
}
