//! Stateless random numbers keyed by integers, for features that exist at every index of an
//! unbounded lattice (furrow lines): any line can be evaluated without storing a table.

/// The SplitMix64 finaliser: a bijective mix of 64 bits with good avalanche.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A key for the lattice of one feature family: `mix(seed ^ mix(family))`.
#[inline]
pub(crate) fn family_key(seed: u64, family: u64) -> u64 {
    mix(seed ^ mix(family))
}

/// A key for item `index` of a family.
#[inline]
pub(crate) fn item_key(family: u64, index: i64) -> u64 {
    mix(family ^ index as u64)
}

/// A uniform number in `[0, 1)` determined by an item key and a salt.
#[inline]
pub(crate) fn unit(key: u64, salt: u64) -> f64 {
    (mix(key ^ salt.wrapping_mul(0xd1b5_4a32_d192_ed03)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform number in `[-1, 1)` determined by an item key and a salt.
#[inline]
pub(crate) fn signed(key: u64, salt: u64) -> f64 {
    2.0 * unit(key, salt) - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let family = family_key(7, 1);
        let xs: Vec<f64> = (0..20_000).map(|k| unit(item_key(family, k), 3)).collect();
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert_ne!(unit(item_key(family, 5), 3), unit(item_key(family_key(8, 1), 5), 3));
        assert_ne!(unit(item_key(family, 5), 3), unit(item_key(family, -5), 3));
        assert_ne!(unit(item_key(family, 5), 3), unit(item_key(family, 5), 4));
    }
}
