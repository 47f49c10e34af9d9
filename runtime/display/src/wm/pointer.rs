//! Pointer input: the window under a point, and the events sent to its painter.

use super::*;

/// A point hit on a window.
#[derive(Clone, Debug, PartialEq)]
pub struct Hit {
    pub window: Guid,
    pub name: Arc<str>,
    /// The point in window-local pixels.
    pub x: f32,
    pub y: f32,
}

impl WindowManager {
    /// The topmost window whose pixel at screen point (x, y) is not transparent (or whose
    /// `hit` method says so). Invisible, failed and unclaimed windows are passed through.
    pub fn hit_test(&self, x: f32, y: f32) -> Option<Hit> {
        let (px, py) = (x.floor() as i32, y.floor() as i32);
        for g in self.stacking.iter().rev() {
            let Some(l) = self.layers.get(g) else { continue };
            let r = l.shown;
            if r.is_empty() || px < r.x || py < r.y || px >= r.right() || py >= r.bottom() {
                continue;
            }
            let (lx, ly) = (x - l.pos.0 as f32, y - l.pos.1 as f32);
            let name = self.props.get(g).map(|p| p.name.clone()).unwrap_or_else(|| "".into());
            let hit = Hit { window: *g, name, x: lx, y: ly };
            let slot = Arc::new(Mutex::new(None));
            let s2 = slot.clone();
            let args = vec![Value::Float(lx as f64), Value::Float(ly as f64)];
            self.ds.call(*g, "hit", args, Some(CallOptions::immediate()), move |o| {
                *s2.lock() = Some(o)
            });
            let answered = slot.lock().take();
            match answered {
                Some(CallOutcome::Accepted(v)) => {
                    if v.first().and_then(Value::as_bool) == Some(true) {
                        return Some(hit);
                    }
                    continue;
                }
                Some(CallOutcome::NoSuchMethod) | None => {}
                Some(_) => continue,
            }
            let Some(pm) = &l.pixmap else { continue };
            let i = ((py - r.y) as usize * pm.width() as usize + (px - r.x) as usize) * 4 + 3;
            if pm.data().get(i).copied().unwrap_or(0) > 0 {
                return Some(hit);
            }
        }
        None
    }

    /// Routes a pointer event: to the window holding the pointer capture (a button is
    /// down), else to the window hit. Sends `enter`/`leave` when the hovered window
    /// changes. Returns the window that received the event.
    pub fn pointer(&mut self, x: f32, y: f32, ev: crate::PointerEvent) -> Option<Hit> {
        use crate::PointerEvent as P;
        let hit = self.hit_test(x, y);
        let target = match self.capture {
            Some((g, _)) => {
                let l = self.layers.get(&g);
                let (lx, ly) = l.map_or((x, y), |l| (x - l.pos.0 as f32, y - l.pos.1 as f32));
                let name = self.props.get(&g).map(|p| p.name.clone()).unwrap_or_else(|| "".into());
                Some(Hit { window: g, name, x: lx, y: ly })
            }
            None => hit.clone(),
        };
        let hovered = hit.as_ref().map(|h| h.window);
        if hovered != self.hover && !matches!(ev, P::Leave) {
            if let Some(old) = self.hover {
                self.send(old, "leave", -1, 0.0, 0.0);
            }
            if let Some(h) = &hit {
                self.send(h.window, "enter", -1, h.x, h.y);
            }
            self.hover = hovered;
        }
        let t = target?;
        match ev {
            P::Move => self.send(t.window, "move", -1, t.x, t.y),
            P::Down(b) => {
                self.capture = Some((t.window, b as i64));
                self.send(t.window, "down", b as i64, t.x, t.y);
            }
            P::Up(b) => {
                if self.capture.is_some_and(|(_, cb)| cb == b as i64) {
                    self.capture = None;
                }
                self.send(t.window, "up", b as i64, t.x, t.y);
            }
            P::Leave => {
                if let Some(old) = self.hover.take() {
                    self.send(old, "leave", -1, 0.0, 0.0);
                }
            }
        }
        Some(t)
    }

    fn send(&self, g: Guid, kind: &str, button: i64, x: f32, y: f32) {
        let args = vec![
            Value::str(kind),
            Value::Int(button),
            Value::Float(x as f64),
            Value::Float(y as f64),
        ];
        self.ds.call(g, "pointer", args, None, |_| {});
    }
}
