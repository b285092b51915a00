//! Mip chains for textures, built on the CPU with a 2x2 box filter (odd sizes clamp the last
//! row and column), so uploads need no blit support from the device.

/// Level 0 (a copy of `rgba8`) down to 1x1.
pub fn chain(width: u32, height: u32, rgba8: &[u8]) -> Vec<(u32, u32, Vec<u8>)> {
    let mut levels = vec![(width, height, rgba8.to_vec())];
    while let Some((w, h, data)) = levels.last() {
        if *w == 1 && *h == 1 {
            break;
        }
        let next = downsample(*w, *h, data);
        levels.push(next);
    }
    levels
}

fn downsample(w: u32, h: u32, src: &[u8]) -> (u32, u32, Vec<u8>) {
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let mut out = vec![0u8; (nw * nh * 4) as usize];
    let at = |x: u32, y: u32, c: usize| src[((y.min(h - 1) * w + x.min(w - 1)) * 4) as usize + c] as u32;
    for y in 0..nh {
        for x in 0..nw {
            for c in 0..4 {
                let s = at(2 * x, 2 * y, c)
                    + at(2 * x + 1, 2 * y, c)
                    + at(2 * x, 2 * y + 1, c)
                    + at(2 * x + 1, 2 * y + 1, c);
                out[((y * nw + x) * 4) as usize + c] = ((s + 2) / 4) as u8;
            }
        }
    }
    (nw, nh, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_ends_at_one_texel_and_averages() {
        let levels = chain(
            4,
            2,
            &[
                0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255, //
                0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255,
            ],
        );
        assert_eq!(levels.iter().map(|l| (l.0, l.1)).collect::<Vec<_>>(), vec![(4, 2), (2, 1), (1, 1)]);
        assert_eq!(&levels[1].2[0..4], &[128, 128, 128, 255]);
        assert_eq!(&levels[2].2[0..4], &[128, 128, 128, 255]);
    }
}
