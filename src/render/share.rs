//! Which camera samples the lattice does not serve share a gather: those of
//! one pixel on one surface, where the lattice says the light there is
//! smooth enough to be taken from one point of the pixel, or of one quarter
//! of the pixel, where it changes within the pixel. Every sample keeps its
//! own direct light; only its irradiance is shared.

use glam::Vec3;

use super::sparse::Record;

/// The samples of its pixel a camera sample may share a gather with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Group {
    /// None: it gathers at its own place (a glossy or bumped material, or
    /// the dense render).
    Alone,
    /// Its pixel's samples on its surface that no lattice corner serves
    /// either (a thin object, a facet between lattice points).
    Pixel,
    /// Its pixel's samples on its surface in the same quarter of the pixel
    /// (0 to 3, [`quarter`]), where the light changes within the pixel: at
    /// most four gathers a pixel and surface, whatever the camera samples
    /// (at 16 per pixel one each gathered 2.6 times the lattice's gathers
    /// on Sponza, and the count grew with every sample). The one nearest
    /// the quarter's centre gathers ([`centre_rank`]).
    Quarter(u8),
}

/// Which quarter of pixel `pixel` film point `film` lies in.
pub(crate) fn quarter(film: (f32, f32), pixel: (u32, u32)) -> u8 {
    u8::from(film.0 - pixel.0 as f32 >= 0.5) | u8::from(film.1 - pixel.1 as f32 >= 0.5) << 1
}

/// The rank of a sample at film point `film` in quarter `q` of pixel
/// `pixel`: its squared distance from the quarter's centre, in units of
/// 2⁻²⁴ pixel². The gather nearest the centre stands for the quarter's
/// mean as the midpoint rule does, exact where the light changes linearly
/// (a random one of the four, as a pixel's first gather is picked, was
/// 1.00 % off the dense nave of 24×18 pixels at 16 spp; 0.76 % with a
/// gather per sample).
pub(crate) fn centre_rank(film: (f32, f32), pixel: (u32, u32), q: u8) -> u32 {
    let cx = pixel.0 as f32 + 0.25 + 0.5 * f32::from(q & 1);
    let cy = pixel.1 as f32 + 0.25 + 0.5 * f32::from(q >> 1);
    let (dx, dy) = (film.0 - cx, film.1 - cy);
    ((dx * dx + dy * dy) * (1u32 << 24) as f32) as u32
}

/// A camera sample of a tile that the lattice does not serve.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Unserved {
    /// Its pixel in the tile.
    pub pixel: usize,
    /// Its place among its pixel's camera samples, in the order they are
    /// offered a gather.
    pub rank: u32,
    pub position: Vec3,
    pub normal: Vec3,
    pub group: Group,
}

/// Which samples take another's gather: for each, `None` (it gathers) or
/// the index of a sample of its pixel and [`Group`], on its surface (the
/// tests of [`Record::covers`], both ways), that gathers and ranks before
/// it.
pub(crate) fn share(samples: &[Unserved], eye: Vec3) -> Vec<Option<usize>> {
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_unstable_by_key(|&i| (samples[i].pixel, samples[i].rank, i));
    let mut takes = vec![None; samples.len()];
    // The current pixel's gathering samples that may share.
    let mut leaders: Vec<usize> = Vec::new();
    let mut pixel = usize::MAX;
    let record = |u: &Unserved| Record {
        position: u.position,
        normal: u.normal,
        e: Vec3::ZERO,
    };
    for i in order {
        let a = &samples[i];
        if a.pixel != pixel {
            pixel = a.pixel;
            leaders.clear();
        }
        if a.group == Group::Alone {
            continue;
        }
        let here = record(a);
        match leaders.iter().find(|&&j| {
            let b = &samples[j];
            b.group == a.group
                && record(b).covers(a.position, a.normal, eye)
                && here.covers(b.position, b.normal, eye)
        }) {
            Some(&j) => takes[i] = Some(j),
            None => leaders.push(i),
        }
    }
    takes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(pixel: usize, rank: u32, position: Vec3, normal: Vec3, group: Group) -> Unserved {
        Unserved {
            pixel,
            rank,
            position,
            normal,
            group,
        }
    }

    #[test]
    fn unserved_samples_share_a_gather_only_on_their_pixel_and_surface() {
        let eye = Vec3::new(0.5, 1.0, 5.0);
        let samples = [
            // Pixel 0: two floor samples, a wall sample, a floor sample that
            // gathers alone; the second floor sample ranks first, so it
            // gathers.
            at(0, 1, Vec3::new(0.1, 0.0, 0.0), Vec3::Y, Group::Pixel),
            at(0, 0, Vec3::new(0.2, 0.0, 0.1), Vec3::Y, Group::Pixel),
            at(0, 2, Vec3::new(1.0, 0.2, 0.1), Vec3::NEG_X, Group::Pixel),
            at(0, 3, Vec3::new(0.3, 0.0, 0.0), Vec3::Y, Group::Alone),
            // Pixel 1: the floor again, but another pixel's.
            at(1, 0, Vec3::new(0.15, 0.0, 0.0), Vec3::Y, Group::Pixel),
            at(1, 1, Vec3::new(0.16, 0.0, 0.0), Vec3::Y, Group::Pixel),
        ];
        assert_eq!(share(&samples, eye), [Some(1), None, None, None, None, Some(4)]);
    }

    #[test]
    fn where_the_light_changes_within_a_pixel_each_quarter_gathers() {
        let eye = Vec3::new(0.5, 1.0, 5.0);
        let floor = |x: f32| Vec3::new(x, 0.0, 0.0);
        // 16 stratified samples of one pixel on the floor, ranked in order:
        // one gather per quarter, each shared by that quarter's samples.
        let samples: Vec<Unserved> = (0..16u32)
            .map(|s| {
                let film = ((s % 4) as f32 / 4.0 + 0.1, (s / 4) as f32 / 4.0 + 0.1);
                let q = quarter((7.0 + film.0, 3.0 + film.1), (7, 3));
                at(0, s, floor(0.01 * s as f32), Vec3::Y, Group::Quarter(q))
            })
            .collect();
        let takes = share(&samples, eye);
        let leaders: Vec<usize> = (0..16).filter(|&i| takes[i].is_none()).collect();
        assert_eq!(leaders, [0, 2, 8, 10]);
        for (i, t) in takes.iter().enumerate() {
            if let Some(j) = t {
                assert_eq!(samples[i].group, samples[*j].group, "sample {i} takes {j}");
            }
        }
        // A wall sample in a quarter gathers apart from the floor's.
        let mut mixed = samples[..2].to_vec();
        mixed.push(at(
            0,
            16,
            Vec3::new(1.0, 0.2, 0.1),
            Vec3::NEG_X,
            Group::Quarter(0),
        ));
        assert_eq!(share(&mixed, eye), [None, Some(0), None]);
        // Quarters: the film point's place in its pixel.
        assert_eq!(quarter((7.2, 3.2), (7, 3)), 0);
        assert_eq!(quarter((7.7, 3.2), (7, 3)), 1);
        assert_eq!(quarter((7.2, 3.7), (7, 3)), 2);
        assert_eq!(quarter((7.7, 3.7), (7, 3)), 3);
        // A quarter's sample nearest its centre ranks first.
        assert_eq!(centre_rank((7.75, 3.75), (7, 3), 3), 0);
        assert_eq!(centre_rank((7.25, 3.75), (7, 3), 2), 0);
        let near = centre_rank((7.3, 3.2), (7, 3), 0);
        let far = centre_rank((7.05, 3.45), (7, 3), 0);
        assert!(0 < near && near < far, "{near} {far}");
    }
}
