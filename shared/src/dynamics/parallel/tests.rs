use super::*;

impl Part for std::ops::Range<usize> {
    fn len(&self) -> usize {
        self.end - self.start
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        (self.start..self.start + mid, self.start + mid..self.end)
    }
}

/// Cuts fall on multiples of the grain and cover the whole once, in order.
#[test]
fn parts_cover_the_whole_in_order() {
    for n in [1, 255, 256, 257, 1000, 4099] {
        let parts = in_parts(
            0..n,
            0,
            256,
            &|r: std::ops::Range<usize>, first| {
                assert_eq!(r.start, first);
                assert!(r.end - r.start <= 256 && first % 256 == 0);
                vec![r]
            },
            &|mut a: Vec<_>, b| {
                a.extend(b);
                a
            },
        );
        let joined: Vec<usize> = parts.into_iter().flatten().collect();
        assert_eq!(joined, (0..n).collect::<Vec<_>>());
    }
}
