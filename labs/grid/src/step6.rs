//! Step 6: mailboxing.
//!
//! A triangle that overlaps several cells is listed in each, so a ray crossing them would test
//! it again and again. Amanatides & Woo's mailbox stored the last ray's id on each triangle;
//! that writes to shared data and breaks with several threads. Instead, keep the last
//! [`SLOTS`] triangle indices this ray tested in a small ring on the stack: a triangle found
//! there is skipped. One tested longer ago may be tested again: that costs time, never the
//! answer. `GridParams::mailboxed()` turns it on.

/// How many recent triangle indices a ray remembers.
pub const SLOTS: usize = 8;

/// The last [`SLOTS`] triangle indices one ray tested.
#[derive(Clone, Copy, Debug)]
pub struct RayMailbox {
    // Step 6: the mailbox's fields.
}

impl RayMailbox {
    /// An empty mailbox, for a new ray.
    pub fn new() -> Self {
        todo!("step 6: an empty mailbox")
    }

    /// Whether triangle `id` was tested by this ray recently (then skip it); if not, remembers
    /// it (the oldest entry makes room).
    pub fn seen(&mut self, id: u32) -> bool {
        todo!("step 6: look up, then remember")
    }
}

impl Default for RayMailbox {
    fn default() -> Self {
        Self::new()
    }
}
