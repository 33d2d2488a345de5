//! What the viewer shares with a page that embeds it (the browser build, `src/web/`): the
//! commands the page sends (a file chosen in its file input or dropped on it), and what the
//! viewer reports back once per frame (started, the error shown, frames drawn), which the
//! page's banner and the browser tests read. On the desktop nothing sends or reads it.

use std::cell::RefCell;
use std::rc::Rc;

use super::command::Command;

/// A handle on the shared [`HostState`]; clones share it.
#[derive(Clone, Debug, Default)]
pub struct Host(Rc<RefCell<HostState>>);

/// The shared state (plain data).
#[derive(Debug, Default)]
pub struct HostState {
    /// Commands for the viewer's next frame.
    pub inbox: Vec<Command>,
    /// The GPU context is up and frames are drawn.
    pub started: bool,
    /// Why the viewer could not start (no adapter, no canvas), said as the page should say it.
    pub fatal: Option<String>,
    /// The error shown in the view (a scene that did not open, with its location), if any.
    pub error: Option<String>,
    /// The last message of the panel ("saved …", "opened …").
    pub message: Option<String>,
    /// The name of the scene on screen.
    pub scene_name: String,
    /// Frames drawn so far.
    pub frames: u64,
    /// The adapter and the chaos game's route ("gpu" or "cpu"), for the page and the tests.
    pub adapter: String,
    pub route: String,
    /// An edit can be undone (for the tests).
    pub can_undo: bool,
    /// The scene has edits not yet saved: leaving the page asks first.
    pub modified: bool,
}

impl Host {
    /// Queues `command` for the viewer's next frame.
    pub fn send(&self, command: Command) {
        self.0.borrow_mut().inbox.push(command);
    }

    /// Reads or changes the shared state.
    pub fn with<R>(&self, f: impl FnOnce(&mut HostState) -> R) -> R {
        f(&mut self.0.borrow_mut())
    }
}
