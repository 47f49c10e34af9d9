//! Where a program's actions are, for the passes that visit every one of them (the
//! locations of script bodies: `crate::locate_scripts`).

use super::{Action, Program, Watch, Widget};
use serde::{Deserialize, Serialize};

/// Where a script's body starts: its file, 1-based line and column.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScriptOrigin {
    pub file: String,
    pub line: u32,
    pub col: u32,
}

impl Program {
    /// Every action of the program: widget handlers, bindings, menu items, watches, and
    /// those of `for each` bodies.
    pub fn actions_mut(&mut self) -> impl Iterator<Item = &mut Action> {
        let (mut widgets, mut watches): (Vec<&mut Widget>, Vec<&mut Watch>) =
            (self.widgets.iter_mut().collect(), self.watches.iter_mut().collect());
        for t in &mut self.templates {
            widgets.extend(t.widgets.iter_mut());
            watches.extend(t.watches.iter_mut());
        }
        let handlers = widgets.into_iter().flat_map(|w| w.handlers.iter_mut());
        handlers
            .flat_map(|h| h.actions.iter_mut())
            .chain(self.bindings.iter_mut().flat_map(|b| b.actions.iter_mut()))
            .chain(
                self.menus
                    .iter_mut()
                    .flat_map(|m| m.items.iter_mut())
                    .flat_map(|i| i.actions.iter_mut()),
            )
            .chain(watches.into_iter().flat_map(|w| w.actions.iter_mut()))
    }
}
