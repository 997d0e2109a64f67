//! The patch templates of the live tracks, by track identity, in slots that are reused:
//! a template is some 6 KB, and a map holding them by value moved them on every growth
//! or rehash of its table and took fresh pages from the system for each larger table
//! (page faults in the window's stage, issue 34). The map holds slot numbers; a slot
//! freed by a track that ended takes the next new track's template.

use swarmpose_vision::features::GrayView;
use swarmpose_vision::temporal::template::PatchTemplate;

use super::ids::IdMap;

/// The templates of the live tracks ([`super::Window`]).
#[derive(Debug, Clone, Default)]
pub(super) struct Templates {
    /// The slot of each track's template.
    slot: IdMap<u32, usize>,
    /// The templates; a free slot holds the template of a track that ended.
    slots: Vec<PatchTemplate>,
    /// The free slots.
    free: Vec<usize>,
}

impl Templates {
    /// The template of track `t`.
    pub(super) fn get_mut(&mut self, t: u32) -> Option<&mut PatchTemplate> {
        let &i = self.slot.get(&t)?;
        self.slots.get_mut(i)
    }

    /// Samples the template of track `t` from `image` at `at` into a slot in place
    /// ([`PatchTemplate::sample_into`]: a template is not built and then copied in, issue
    /// 34), in place of the one it had; false, and nothing kept, when
    /// [`PatchTemplate::sample`] gives `None` (the track keeps the template it had).
    pub(super) fn sample(&mut self, t: u32, image: GrayView<'_>, at: (f32, f32)) -> bool {
        let (i, pushed) = match self.free.pop() {
            Some(i) => (i, false),
            None => {
                self.slots.push(PatchTemplate::empty());
                (self.slots.len() - 1, true)
            }
        };
        if !self
            .slots
            .get_mut(i)
            .is_some_and(|s| s.sample_into(image, at))
        {
            // The slot goes back as it was: free, or not there.
            if pushed {
                self.slots.pop();
            } else {
                self.free.push(i);
            }
            return false;
        }
        if let Some(old) = self.slot.insert(t, i) {
            self.free.push(old);
        }
        true
    }

    /// Keeps the templates of the tracks for which `live` holds; the others' slots are
    /// freed.
    pub(super) fn retain(&mut self, live: impl Fn(u32) -> bool) {
        let free = &mut self.free;
        self.slot.retain(|&t, &mut i| {
            let keep = live(t);
            if !keep {
                free.push(i);
            }
            keep
        });
    }

    /// Forgets every template (the buffers are kept).
    pub(super) fn clear(&mut self) {
        self.slot.clear();
        self.slots.clear();
        self.free.clear();
    }

    /// Templates held (live tracks with one).
    #[cfg(test)]
    pub(super) fn len(&self) -> usize {
        self.slot.len()
    }

    /// Heap bytes held.
    pub(super) fn heap_bytes(&self) -> usize {
        self.slot.capacity() * (size_of::<u32>() + size_of::<usize>())
            + self.slots.capacity() * size_of::<PatchTemplate>()
            + self.free.capacity() * size_of::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Slots are reused: templates of tracks that ended make room for new ones, each
    /// track finds its own template (by its patch), and clearing forgets them all.
    #[test]
    fn tracks_find_their_templates_in_reused_slots() {
        let (w, h) = (64, 48);
        let pixels: Vec<u8> = (0..w * h)
            .map(|i| ((i * 7919 + (i / w) * 31) % 251) as u8)
            .collect();
        let image = GrayView {
            width: w,
            height: h,
            data: &pixels,
        };
        let at = |k: u32| (12.0 + k as f32 * 3.0, 20.0);
        let patch = |k: u32| PatchTemplate::sample(image, at(k)).expect("inside");
        let mut templates = Templates::default();
        for t in 0..8 {
            assert!(templates.sample(t, image, at(t)));
        }
        templates.retain(|t| t % 2 == 0);
        assert_eq!(templates.len(), 4);
        for t in 8..12 {
            assert!(templates.sample(t, image, at(t)));
        }
        // The four freed slots took the four new templates.
        assert_eq!(templates.slots.len(), 8);
        for t in 0..12 {
            let kept = t % 2 == 0 || t >= 8;
            match templates.get_mut(t) {
                Some(tpl) => assert!(kept && *tpl == patch(t), "track {t}"),
                None => assert!(!kept, "track {t}"),
            }
        }
        // A new template of a track takes a new slot and frees its old one.
        assert!(templates.sample(4, image, at(9)));
        assert!(templates.get_mut(4).is_some_and(|tpl| *tpl == patch(9)));
        assert_eq!((templates.slots.len(), templates.free.len()), (9, 1));
        // A patch outside the image keeps nothing: the track keeps its template, and the
        // slots are as they were (a free one taken goes back, a pushed one is removed).
        assert!(!templates.sample(4, image, (-5.0, 20.0)));
        assert!(templates.get_mut(4).is_some_and(|tpl| *tpl == patch(9)));
        assert_eq!((templates.slots.len(), templates.free.len()), (9, 1));
        assert!(templates.sample(12, image, at(12)));
        assert!(!templates.sample(13, image, (-5.0, 20.0)));
        assert!(templates.get_mut(13).is_none());
        assert_eq!((templates.slots.len(), templates.free.len()), (9, 0));
        templates.clear();
        assert_eq!(templates.len(), 0);
        assert!(templates.get_mut(0).is_none());
    }
}
