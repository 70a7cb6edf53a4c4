//! How the tracking list's predictions compare with what the camera then
//! sees.

/// How the tracking list's predictions compare with what the camera then
/// sees: the landmarks the chosen heading was predicted to keep in view,
/// against the landmarks in the last frame of the step taken along it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PredictionCheck {
    /// Steps compared.
    pub steps: u64,
    /// Mean landmarks predicted in view.
    pub mean_predicted: f64,
    /// Mean landmarks the camera delivered.
    pub mean_seen: f64,
}

impl PredictionCheck {
    fn add(&mut self, predicted: usize, seen: usize) {
        let n = self.steps as f64;
        self.mean_predicted = (self.mean_predicted * n + predicted as f64) / (n + 1.0);
        self.mean_seen = (self.mean_seen * n + seen as f64) / (n + 1.0);
        self.steps += 1;
    }
}

/// The check so far, and the prediction of the step under way waiting to
/// be compared at the next decision.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Predictions {
    /// The steps compared so far.
    pub(super) check: PredictionCheck,
    /// Landmarks the last evaluated heading was predicted to keep in view.
    predicted: Option<usize>,
    /// How many the camera delivered in the latest frame of the step taken.
    seen: Option<usize>,
}

impl Predictions {
    /// A heading was evaluated: `predicted` landmarks in view along it
    /// (`None` without a feasible heading), none seen yet.
    pub(super) fn predict(&mut self, predicted: Option<usize>) {
        self.predicted = predicted;
        self.seen = None;
    }

    /// A frame of the step came with `seen` landmarks.
    pub(super) fn saw(&mut self, seen: usize) {
        self.seen = Some(seen);
    }

    /// At a decision: the step just taken is compared, if it was both
    /// predicted and seen.
    pub(super) fn settle(&mut self) {
        if let (Some(predicted), Some(seen)) = (self.predicted.take(), self.seen.take()) {
            self.check.add(predicted, seen);
        }
    }
}
