//! Views of multi-view (stereo) OpenEXR files: which views a file holds, which one is its
//! default, which channels belong to each, and a file seen as one view (`--view`).
//!
//! OpenEXR's "Storing Multi-View Images in OpenEXR Files"
//! (<https://openexr.com/en/latest/MultiViewOpenEXR.html>, the source text is
//! `website/MultiViewOpenEXR.rst` in AcademySoftwareFoundation/openexr) describes two
//! schemes; both are read here, from the attributes the `exr` crate parses
//! (`LayerAttributes::multi_view_names` for `multiView`, `LayerAttributes::view_name` for
//! `view`):
//!
//! - **Multi-part** (the preferred scheme): "Multi-part EXR files use the `view` attribute
//!   within the header for each part to indicate that all the channels within that part are
//!   associated with that view"; "The `view` attribute of the first part within the file
//!   indicates which view is the default view"; channel names do not include the view (each
//!   view has its own `R`); a part without `view` holds channels of no view, and "this part
//!   cannot be the first part". A file whose first part has no `view` while others have one
//!   therefore names no default: reading it needs `--view`.
//! - **Single part**: a `multiView` attribute lists the views and "the first listed view
//!   (array element 0) is always the default view". A channel's view is its penultimate
//!   period-delimited component (`view.channel`, `layer.view.channel`); "all channel
//!   instances whose names contain no periods (for example, R, G, B, A, or Z) belong to the
//!   default view"; other names with a period belong to no view (`background.data`).
//!
//! "Software reading files should look for a `view` attribute and fall back to the
//! `multiView` attribute if it is not present": so a multi-part file is read by its parts'
//! `view` attributes, and by `multiView` (with the single-part naming across its parts) only
//! when no part has `view` (the document says the two should not be combined; a file that
//! does is read rather than refused). Parts whose `multiView` lists disagree name no
//! default. A single-part file with a `view` attribute and no `multiView` is a file of one
//! view ("Files with Only One View").
//!
//! Seen as one view, a file holds that view's channels, named without the view (`right.R`
//! reads as `R`, `depth.right.Z` as `depth.Z`), and the channels of no view, except where a
//! channel of the view has the same name: a single-part file's `depth.Z` belongs to no view
//! by the rule above, yet is the default view's depth when the other view has
//! `depth.right.Z`; reading `right` takes `depth.right.Z`, reading the default takes
//! `depth.Z`. Presets then find channels in the view exactly as in a file of one view.

use exr::meta::header::Header;

/// How a file ties channels to views.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Each part's `view` attribute (one entry per part; `None`: a part of no view).
    Parts(Vec<Option<String>>),
    /// `multiView` and the view as the penultimate component of channel names.
    Names,
}

/// The views a file holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Views {
    /// The views, in the file's order: `multiView`'s list, or the parts' `view` attributes in
    /// part order (each once).
    pub names: Vec<String>,
    /// The default view, when the file names one.
    pub default: Option<String>,
    /// Why there is no default, when there is none (for messages).
    pub no_default: Option<String>,
    pub scheme: Scheme,
}

/// A multi-view part's name without its view: Blender names the part of a pass of one view
/// `layer.pass-view` (`ViewLayer.Combined-left`, its `view` attribute `left`) and its
/// channels `layer.pass.X`, which begin with what is left. The name as it is otherwise.
pub fn part_name_without_view(name: &str, view: Option<&str>) -> String {
    view.and_then(|v| name.strip_suffix(&format!("-{v}")))
        .unwrap_or(name)
        .to_string()
}

/// The layer of a channel's name, OpenEXR's way: all before its last period (`diffuse` of
/// `diffuse.R`, none of `R`). In the one-part scheme a layer that a view other than the
/// default writes as its own (`diffuse.right.R`) is a layer of each view, so its channels
/// of no view (`diffuse.R`, `diffuse.A`) are the default view's alone, even where the
/// other view lacks one of them: the reader (`FileInfo`'s view planning) and the writer
/// (`exr_parts`, a stereo file split into parts by view) both go by it.
pub fn layer_of(name: &str) -> Option<&str> {
    name.rsplit_once('.').map(|(layer, _)| layer)
}

impl Views {
    /// Finds the views of a file from its headers (parts), or `None` for a file of no views.
    pub fn of(headers: &[Header]) -> Option<Views> {
        let text = crate::io::channels::name_of;
        let part_views: Vec<Option<String>> = headers
            .iter()
            .map(|h| h.own_attributes.view_name.as_ref().map(text))
            .collect();
        let lists: Vec<Vec<String>> = headers
            .iter()
            .filter_map(|h| h.own_attributes.multi_view_names.as_ref())
            .map(|list| list.iter().map(text).collect::<Vec<_>>())
            .filter(|list| !list.is_empty())
            .collect();
        if headers.len() > 1 && part_views.iter().any(Option::is_some) {
            let mut names: Vec<String> = Vec::new();
            for view in part_views.iter().flatten() {
                if !names.contains(view) {
                    names.push(view.clone());
                }
            }
            let default = part_views[0].clone();
            return Some(Views {
                names,
                no_default: default
                    .is_none()
                    .then(|| "its first part has no view attribute".to_string()),
                default,
                scheme: Scheme::Parts(part_views),
            });
        }
        if let Some(first) = lists.first() {
            let mut names: Vec<String> = Vec::new();
            for list in &lists {
                for view in list {
                    if !names.contains(view) {
                        names.push(view.clone());
                    }
                }
            }
            let agree = lists.iter().all(|list| list == first);
            return Some(Views {
                default: agree.then(|| first[0].clone()),
                no_default: (!agree)
                    .then(|| "its parts' multiView attributes list different views".to_string()),
                names,
                scheme: Scheme::Names,
            });
        }
        if let [Some(view)] = &part_views[..] {
            return Some(Views {
                names: vec![view.clone()],
                default: Some(view.clone()),
                no_default: None,
                scheme: Scheme::Parts(part_views.clone()),
            });
        }
        None
    }

    /// The view a channel of `part` named `name` belongs to (`None`: no view).
    pub fn view_of(&self, part: usize, name: &str) -> Option<String> {
        match &self.scheme {
            Scheme::Parts(parts) => parts.get(part).cloned().flatten(),
            Scheme::Names => {
                let components: Vec<&str> = name.split('.').collect();
                match components[..] {
                    [_] => self.default.clone(),
                    [.., view, _] if self.names.iter().any(|n| n == view) => Some(view.to_string()),
                    _ => None,
                }
            }
        }
    }

    /// A channel's name without its view (`right.R` → `R`, `a.right.Z` → `a.Z`): what a
    /// preset looks for. Names of the multi-part scheme carry no view and stay as they are.
    pub fn strip(&self, name: &str, view: &str) -> String {
        if self.scheme != Scheme::Names {
            return name.to_string();
        }
        let mut components: Vec<&str> = name.split('.').collect();
        if components.len() >= 2 && components[components.len() - 2] == view {
            components.remove(components.len() - 2);
        }
        components.join(".")
    }

    /// The views, the default first (then in the file's order): the order in which a run
    /// reads every view, and an output of every view holds them.
    pub fn in_order(&self) -> Vec<String> {
        let mut names = self.names.clone();
        if let Some(default) = &self.default {
            names.retain(|n| n != default);
            names.insert(0, default.clone());
        }
        names
    }

    /// The views for messages: `left (default), right`.
    pub fn list(&self) -> String {
        self.names
            .iter()
            .map(|n| {
                if self.default.as_deref() == Some(n) {
                    format!("{n} (default)")
                } else {
                    n.clone()
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The view to read: `asked` if the file holds it, else the default; or why neither
    /// can be read (a message listing the views).
    pub fn choose(&self, asked: Option<&str>) -> Result<String, String> {
        match asked {
            Some(view) if self.names.iter().any(|n| n == view) => Ok(view.to_string()),
            Some(view) => Err(format!(
                "the file has no view '{view}'; its views are {}: choose one with --view",
                self.list()
            )),
            None => self.default.clone().ok_or_else(|| {
                format!(
                    "the file holds the views {} and names no default ({}): choose one \
                     with --view",
                    self.list(),
                    self.no_default.as_deref().unwrap_or("no default view")
                )
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Views {
        Views {
            names: list.iter().map(|s| s.to_string()).collect(),
            default: Some(list[0].to_string()),
            no_default: None,
            scheme: Scheme::Names,
        }
    }

    #[test]
    fn single_part_views_follow_the_penultimate_component() {
        let v = names(&["left", "right"]);
        assert_eq!(v.view_of(0, "R").as_deref(), Some("left"));
        assert_eq!(v.view_of(0, "right.R").as_deref(), Some("right"));
        assert_eq!(v.view_of(0, "lighting.right.R").as_deref(), Some("right"));
        assert_eq!(v.view_of(0, "left.R").as_deref(), Some("left"));
        // A period and no view: a channel of no view.
        assert_eq!(v.view_of(0, "background.data"), None);
        // `layer.view` is not the view's channel (the document's `speed.left`).
        assert_eq!(v.view_of(0, "speed.left"), None);
        assert_eq!(v.strip("depth.right.Z", "right"), "depth.Z");
        assert_eq!(v.strip("right.R", "right"), "R");
        assert_eq!(v.strip("R", "left"), "R");
    }

    #[test]
    fn choosing_a_view_names_the_views_when_it_cannot() {
        let v = names(&["left", "right"]);
        assert_eq!(v.choose(None).unwrap(), "left");
        assert_eq!(v.choose(Some("right")).unwrap(), "right");
        let err = v.choose(Some("centre")).unwrap_err();
        assert!(
            err.contains("'centre'") && err.contains("left (default), right"),
            "{err}"
        );
        let v = Views {
            default: None,
            no_default: Some("its first part has no view attribute".into()),
            ..names(&["left", "right"])
        };
        let err = v.choose(None).unwrap_err();
        assert!(
            err.contains("left, right") && err.contains("first part"),
            "{err}"
        );
    }
}
