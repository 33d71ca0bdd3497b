//! The window's keys: what each key press does, and which movement keys the fly camera reads (README "Viewer keys" lists the same table).

use std::collections::HashSet;

use winit::keyboard::KeyCode;

use super::camera_control::FlyKeys;

/// What a key press asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Tab: orbit ↔ fly.
    ToggleController,
    /// F12: write the frame as PNG, EXR and JSON sidecar.
    Screenshot,
    /// R: start or stop recording a camera path.
    ToggleRecording,
    /// Space: play the camera path (recorded or `--play`), or stop it.
    TogglePlayback,
    /// Home: back to the scene's own camera.
    ResetCamera,
    /// F: orbit framed on the scene's bounds.
    FrameScene,
    /// 1–9: go to a bookmark.
    RecallBookmark(usize),
    /// Ctrl+1–9: store the camera as a bookmark.
    StoreBookmark(usize),
    /// F1: show or hide the panel.
    TogglePanel,
    /// Escape: close the window.
    Quit,
}

/// The action of pressing `key` with Ctrl held or not; `None` for keys with no action (the movement keys are read by [`fly_keys`]).
pub fn action(key: KeyCode, ctrl: bool) -> Option<Action> {
    let digit = match key {
        KeyCode::Digit1 => Some(0),
        KeyCode::Digit2 => Some(1),
        KeyCode::Digit3 => Some(2),
        KeyCode::Digit4 => Some(3),
        KeyCode::Digit5 => Some(4),
        KeyCode::Digit6 => Some(5),
        KeyCode::Digit7 => Some(6),
        KeyCode::Digit8 => Some(7),
        KeyCode::Digit9 => Some(8),
        _ => None,
    };
    if let Some(slot) = digit {
        return Some(if ctrl {
            Action::StoreBookmark(slot)
        } else {
            Action::RecallBookmark(slot)
        });
    }
    Some(match key {
        KeyCode::Tab => Action::ToggleController,
        KeyCode::F12 => Action::Screenshot,
        KeyCode::KeyR if !ctrl => Action::ToggleRecording,
        KeyCode::Space => Action::TogglePlayback,
        KeyCode::Home => Action::ResetCamera,
        KeyCode::KeyF if !ctrl => Action::FrameScene,
        KeyCode::F1 => Action::TogglePanel,
        KeyCode::Escape => Action::Quit,
        _ => return None,
    })
}

/// The fly camera's movement from the keys held: W/S forwards and back, D/A right and left, E/Q up and down, Shift fast (either Shift key).
pub fn fly_keys(held: &HashSet<KeyCode>) -> FlyKeys {
    let axis = |plus: KeyCode, minus: KeyCode| {
        f32::from(u8::from(held.contains(&plus))) - f32::from(u8::from(held.contains(&minus)))
    };
    FlyKeys {
        forward: axis(KeyCode::KeyW, KeyCode::KeyS),
        right: axis(KeyCode::KeyD, KeyCode::KeyA),
        up: axis(KeyCode::KeyE, KeyCode::KeyQ),
        fast: held.contains(&KeyCode::ShiftLeft) || held.contains(&KeyCode::ShiftRight),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_recall_and_ctrl_digits_store_bookmarks() {
        assert_eq!(
            action(KeyCode::Digit1, false),
            Some(Action::RecallBookmark(0))
        );
        assert_eq!(
            action(KeyCode::Digit9, true),
            Some(Action::StoreBookmark(8))
        );
        assert_eq!(action(KeyCode::Digit0, false), None);
    }

    #[test]
    fn every_documented_key_has_its_action() {
        for (key, expected) in [
            (KeyCode::Tab, Action::ToggleController),
            (KeyCode::F12, Action::Screenshot),
            (KeyCode::KeyR, Action::ToggleRecording),
            (KeyCode::Space, Action::TogglePlayback),
            (KeyCode::Home, Action::ResetCamera),
            (KeyCode::KeyF, Action::FrameScene),
            (KeyCode::F1, Action::TogglePanel),
            (KeyCode::Escape, Action::Quit),
        ] {
            assert_eq!(action(key, false), Some(expected), "{key:?}");
        }
        // Movement keys act only while held.
        for key in [
            KeyCode::KeyW,
            KeyCode::KeyA,
            KeyCode::KeyQ,
            KeyCode::ShiftLeft,
        ] {
            assert_eq!(action(key, false), None, "{key:?}");
        }
    }

    #[test]
    fn held_keys_give_the_fly_axes() {
        let held: HashSet<KeyCode> = [KeyCode::KeyW, KeyCode::KeyA, KeyCode::ShiftRight].into();
        assert_eq!(
            fly_keys(&held),
            FlyKeys {
                forward: 1.0,
                right: -1.0,
                up: 0.0,
                fast: true
            }
        );
        // Opposite keys cancel.
        let held: HashSet<KeyCode> = [KeyCode::KeyE, KeyCode::KeyQ, KeyCode::KeyS].into();
        let keys = fly_keys(&held);
        assert_eq!((keys.forward, keys.up, keys.fast), (-1.0, 0.0, false));
        assert!(!fly_keys(&HashSet::new()).moving());
    }
}
