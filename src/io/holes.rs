//! Holes in a sequence found on disk: the frames missing between its first and last, at its
//! smallest step, and words for a sequence whose frames step by more than one amount.

use crate::io::sequence::MAX_FRAMES;

/// The frames missing between the first and last of `found` (sorted, distinct), at the
/// sequence's smallest step (a sequence rendered on twos has no holes at the odd frames); at
/// most [`MAX_FRAMES`] listed. Where the frames step by more than one amount (see
/// [`mixed_steps`]) the smallest is taken: a render on ones that lost every other frame in a
/// stretch (a farm's second worker failing: 1, 2, 3, 5, 7, 9) is then said to miss them,
/// where the commonest step (2) had called it complete. A sequence on twos with a frame
/// between two of them is then said to miss the frames on ones, which the warning words as
/// mixed steps: a wrong "complete" is the costlier mistake.
pub fn holes(found: &[i64]) -> Vec<i64> {
    let Some(step) = found.windows(2).map(|w| (w[1] - w[0]).max(1)).min() else {
        return Vec::new();
    };
    let mut holes = Vec::new();
    for w in found.windows(2) {
        let mut f = w[0] + step;
        while f < w[1] && holes.len() < MAX_FRAMES {
            holes.push(f);
            f += step;
        }
    }
    holes
}

/// Where the frames of `found` (sorted, distinct) step by more than one amount, words for a
/// holes warning: "its frames step by 2 mostly, by 1 in places, so frames on ones are
/// listed"; `None` where every step is one amount, or the smallest is also the commonest.
pub fn mixed_steps(found: &[i64]) -> Option<String> {
    let mut steps: Vec<i64> = found.windows(2).map(|w| (w[1] - w[0]).max(1)).collect();
    steps.sort_unstable();
    let smallest = *steps.first()?;
    let (mut commonest, mut most, mut run) = (smallest, 0, 0);
    for (k, &s) in steps.iter().enumerate() {
        run = if k > 0 && steps[k - 1] == s {
            run + 1
        } else {
            1
        };
        if run > most {
            (commonest, most) = (s, run);
        }
    }
    (commonest != smallest).then(|| {
        format!(
            "its frames step by {commonest} mostly, by {smallest} in places, so the frames \
             missing at steps of {smallest} are listed"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holes_are_the_frames_missing_at_the_sequence_s_step() {
        assert_eq!(holes(&[1, 2, 3, 6, 7, 9]), [4, 5, 8]);
        // On twos: no holes at the odd frames, one at 7.
        assert_eq!(holes(&[1, 3, 5, 9, 11]), [7]);
        assert_eq!(mixed_steps(&[1, 3, 5, 9, 11]), None);
        // On ones, every other frame lost in a stretch (the commonest step 2): the smallest.
        assert_eq!(holes(&[1, 2, 3, 5, 7, 9]), [4, 6, 8]);
        assert_eq!(holes(&[-1, 1, 2, 4]), [0, 3]);
        let mut far = vec![0, 3];
        far.extend(5..20);
        assert_eq!(holes(&[-1, 1, 2, 4, 20]), far);
        // On twos with a frame between two of them: said as mixed steps.
        assert_eq!(holes(&[1, 3, 5, 6, 7, 9, 13]), [2, 4, 8, 10, 11, 12]);
        let mixed = mixed_steps(&[1, 3, 5, 6, 7, 9, 13]).unwrap();
        assert!(mixed.contains("by 2 mostly, by 1 in places"), "{mixed}");
        assert_eq!(holes(&[10, 12, 13, 16]), [11, 14, 15]);
        assert!(holes(&[4]).is_empty());
        assert_eq!(mixed_steps(&[4]), None);
    }
}
