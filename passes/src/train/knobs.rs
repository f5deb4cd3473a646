//! The trainer's knobs. The defaults were chosen on CUPS' `inlay
//! render-views` set (24 views of 48 × 48; `docs/benchmarks.md`,
//! "Training"): ε 0.05 → 4 took the held-out PSNR from 22 to 25 dB (the
//! relative loss on pixels near black, most of a view, drowned the rest),
//! density step 20 → 5 to 28.5 dB.

/// Every knob of `inlay train`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrainKnobs {
    /// Nodes per axis of the final grid (the longest axis; the others in
    /// proportion to the bounds).
    pub resolution: u32,
    /// Coarse-to-fine stages: the grid starts at resolution / 2^(stages−1)
    /// and doubles after each stage's share of the steps
    /// ([`Self::first_stage_share`]).
    pub stages: u32,
    /// Share of the steps the first, coarsest stage takes when there are
    /// several; the later stages split the rest evenly. A step at a
    /// quarter of the resolution costs a quarter of one at the full
    /// resolution, and the coarse stage clears the free space the finer
    /// ones inherit. Half (2:1:1 over three stages) against a third
    /// (1:1:1): on ROOM at 128 nodes the haze in front of the surfaces
    /// went from 26–35 % of their light to 19–27 % and the held-out views
    /// gained 0.5–1 dB; every bundled scene trained in 13–17 % less time
    /// with less haze (DOG and BOOKS 0.1–0.2 dB lower); 1:1:4 left 42–51 %
    /// (`docs/benchmarks.md`, issue 25's fourteenth pass).
    pub first_stage_share: f64,
    /// How a stage's densities carry onto the next, finer grid: each is
    /// multiplied by r^p, r the ratio of the node spacings (about 2), p this
    /// ([`super::trainer::refine`]). 0 carries the field unchanged; 1
    /// carries each node's optical depth per spacing, so a surface rises
    /// as steeply per node as it did on the coarse grid (the coarse stage
    /// fits a surface's opacity to one coarse cell, and the photographs of
    /// an untextured surface never ask the finer stages to steepen it).
    /// Where the interpolated density crosses zero, the surfaces, is kept.
    /// Between 0 and 1; 0 by default, and [`REFINE_EXPONENT_BEHIND_RANDOM`]
    /// where the background is random ([`Self::auto_refine_exponent`],
    /// what `inlay train` takes unless told).
    pub refine_density_exponent: f64,
    /// Adam steps.
    pub iterations: u32,
    /// Rays per step: [`Self::pixels_per_step`] pixels of
    /// [`Self::rays_per_pixel`] rays each.
    pub batch: u32,
    /// The march's samples along the field's diagonal, on the final grid;
    /// a coarser stage takes [`Self::coarse_samples`] × as many per node
    /// spacing ([`Self::stage_samples`]).
    pub samples_per_ray: u32,
    /// A coarse stage's samples per node spacing as a multiple of the
    /// final grid's (at most [`Self::samples_per_ray`] along the
    /// diagonal): 1 marches every stage alike; 4 on a three-stage run
    /// marches every stage at [`Self::samples_per_ray`], as before issue
    /// 25's nineteenth pass. The default, 2, halves the first stage's
    /// samples: at 1 ROOM's surfaces moved 0.1–0.4 spacings further off
    /// and its held-out views lost 0.1 dB, at 2 they kept their figures
    /// (`docs/benchmarks.md`).
    pub coarse_samples: f64,
    /// Colour step size, as a fraction of the pixels' mean radiance; a
    /// colour above [`super::trainer::RELATIVE_STEP_FLOOR`] × the loss's
    /// floor steps by this fraction of itself (a lamp's light, not the
    /// room's).
    pub rate: f64,
    /// Density step size, in units of 1 / the field's diagonal.
    pub density_rate: f64,
    /// Factor the step sizes decay by over the run (exponentially).
    pub rate_decay: f64,
    /// The relative loss's floor, as a fraction of the mean radiance.
    pub epsilon: f64,
    /// The radiance the rates, the loss's floor and the starting grey are
    /// fractions of; None: the mean over the training poses of each
    /// one's mean luminance, pixels that look past the bounds counted
    /// black and poses far brighter than the median one left out
    /// ([`super::trainer::radiance_scale`]), so that a light outside the
    /// field that a few views see (ROOM's Cycles set sees its bulb in
    /// front of the box) does not set it.
    pub scale: Option<f64>,
    /// Total variation's step on colour after each Adam step: each value
    /// moves by 2 × this × its differences to its six neighbours (at most
    /// [`super::tv::MAX_TV_WEIGHT`]; bounded beyond
    /// [`Self::tv_colour_edge`]). 0 by default: 1e-3 raised the Cycles
    /// sets' held-out views by up to 1.1 dB, but, scored over the pixels'
    /// area, lowered the means of DOG's, CUPS', BOOKS' and ROOM's 48 views
    /// of 160 × 120 by 0.3–1.3 dB (`docs/benchmarks.md`, issue 25's
    /// twenty-seventh and twenty-eighth passes).
    pub tv_colour: f64,
    /// The colour difference between neighbouring nodes, as a fraction of
    /// the radiance scale ([`Self::scale`]), beyond which the colour's
    /// total variation pulls it by a bounded amount rather than in
    /// proportion ([`super::tv::TvWeights::colour_edge`]): a speckle
    /// below it is smoothed, a lamp's radiance above it is kept. 0:
    /// squared differences everywhere.
    pub tv_colour_edge: f64,
    /// The same for density. 3e-3 by default: DOG trained at 128 nodes
    /// from 48 views of 160 × 120 left its surfaces painted on a haze 11–16
    /// node spacings in front of the recipe's without it (held-out views
    /// 24–30 dB), 2–4 with it (29–33 dB); 1e-2 and 3e-2 a little worse
    /// (`docs/benchmarks.md`, issue 25's eighth pass).
    pub tv_density: f64,
    /// The density difference between neighbouring nodes, as an optical
    /// depth per node spacing (σ·h), beyond which the total variation
    /// pulls it by a bounded amount rather than in proportion
    /// ([`super::tv::TvWeights::density_edge`]): a haze below it is
    /// smoothed as before, a surface's rise above it is left sharp. 0:
    /// squared differences everywhere, which at the default weight
    /// diffuse a density step over 12 nodes in 2000 steps. With the
    /// distortion loss it is what lets a surface's rise be sharp
    /// (`docs/fidelity.md`, "Thirty-third pass"). 0.1 by default: with
    /// squared differences PLANTS' lamp, a sphere a few nodes across,
    /// faded over longer runs (at 3000 steps its views kept 0.73–0.80 of
    /// their light, 0.93–0.97 with the edge), and at 3000 steps the edge
    /// took ROOM's median depth error from 2.1–3.8 node spacings to
    /// 1.4–2.4 (`docs/benchmarks.md`, issue 25's fourteenth pass).
    pub tv_edge: f64,
    /// Weight of the density's sparsity prior, taken in total variation's
    /// step ([`super::tv::TvWeights::sparsity`]; its scale its own edge,
    /// [`Self::sparsity_edge`]): pulls a haze toward zero, an opaque surface
    /// hardly at all. 0 leaves it out. 1e-3 by default: at 128 nodes from
    /// 48 views of 160 × 120 it took ROOM's median depth error from
    /// 1.4–2.4 node spacings to 1.0–1.2 and CUPS' worst view's from 4.3 to
    /// 3.4 at the same held-out PSNR, and cost PLANTS, whose lamp and
    /// foliage train as faint glowing density, 0.5 dB; 2e-3 and 3e-3 put
    /// ROOM's surfaces about a spacing behind the recipe's
    /// (`docs/benchmarks.md`, issue 25's fifteenth pass; again at the
    /// twenty-third: 2e-3 brings DOG's surfaces and CUPS' lowest view
    /// closer, puts ROOM's behind, costs PLANTS 2 dB). Behind a random
    /// background, whose steeper refinement leaves a haze in front of the
    /// surfaces, [`SPARSITY_BEHIND_RANDOM`] ([`Self::auto_sparsity`]).
    /// Stated for 128 nodes; finer grids apply less
    /// ([`Self::sparsity_at`]).
    pub sparsity: f64,
    /// The sparsity prior's edge, an optical depth per node spacing (σ·h;
    /// [`super::tv::TvWeights::sparsity_edge`]): the density its pull is
    /// strongest at. A haze well below it is pulled in proportion; matter
    /// well above it, hardly at all. 0: σ₊² everywhere. 0.03 by default
    /// (behind a random background [`SPARSITY_EDGE_BEHIND_RANDOM`],
    /// [`Self::auto_sparsity_edge`]): at the edge of 0.1 it had shared
    /// with total variation, the prior pulled hardest on PLANTS' foliage
    /// (about 0.09 a spacing) and, from its Cycles set, trained it with
    /// 0.42 of its optical depth, so the lamp seen through it lit the
    /// inserted toy 1.6 times too brightly; at 0.03 the foliage kept 0.68
    /// of it and the toy read 1.12, for 0.2–0.6 spacings more depth error
    /// on DOG's, CUPS' and BOOKS' first views (`docs/benchmarks.md`, issue
    /// 25's thirty-third pass).
    pub sparsity_edge: f64,
    /// The distortion loss's weight λ ([`super::render_ray_with_gradient`]):
    /// pulls each ray's weight into one short stretch, surfaces into thin
    /// shells; 0 leaves it out. On DOG at 128 nodes from 64 views of 256²,
    /// 0.1 raised the held-out views by 1.3 and 2.2 dB, 0.5 overshot
    /// (`docs/benchmarks.md`, "Distortion loss"); with today's other
    /// defaults 0.03 and 0.1 moved DOG's surfaces from 48 views of
    /// 160 × 120 further off, the haze in front of them thicker (issue
    /// 25's twenty-third pass). Off by default. From a field the defaults
    /// cleared (`--resume`), 0.5 with [`Self::tv_edge`] at 0.02 thinned
    /// DOG's Cycles floor (2.46 → 1.72–1.76 node spacings); as a phase
    /// after the stages it cost PLANTS, whose foliage is a medium,
    /// 1.0–2.2 dB (issue 25's thirty-fifth pass).
    pub distortion: f64,
    /// The depth loss's weight μ ([`super::depth`]) on the rays whose
    /// frame has a depth map (`depth_file_path`): holds each ray's weight
    /// at the surface the map records, which a photograph of a plain
    /// surface cannot place; 0 ignores the maps. Photographs without depth
    /// maps train the same at any weight. With Cycles' depth maps every
    /// Cycles set's held-out views came within half a node spacing; with
    /// noisy ones (a phone's) 0.3 placed BOOKS' surfaces nearer than 1
    /// (`docs/benchmarks.md`, issue 25's thirty-sixth pass).
    pub depth_weight: f64,
    /// The depth loss's tolerance s, in node spacings of the final grid:
    /// within it the loss is quadratic, beyond it linear (a depth map's
    /// noise and a surface's place within its cell). 3 instead of 1
    /// changed DOG's noisy-map depth errors by at most 0.02 spacings.
    pub depth_tolerance: f64,
    /// Train twice where the photographs leave surfaces open: the planes
    /// through the surfaces the first run's field places complete, as
    /// depths, the training pixels whose weight it spreads wide, and a
    /// second run trains from the start holding them there
    /// ([`super::planes`], [`super::completing`]). Where some training
    /// frame has no depth map, from the start (not `--resume`), at a depth
    /// weight above 0. On the Cycles sets from photographs alone the
    /// held-out views came within a node spacing on 9 of 10 views (2 of
    /// 10 from one run); two runs of [`TWO_RUN_SHARE`] of the steps took
    /// 1.4–1.7 times one run's time (`docs/benchmarks.md`, issue 25's
    /// forty-fourth pass).
    pub planes: bool,
    /// Each step's rays end on a random colour behind the field (each
    /// channel uniform over 0 to twice the photographs' mean radiance)
    /// rather than on the fixed background: a field a ray partly sees
    /// through where its photograph shows a surface then pays for it, so
    /// surfaces train opaque rather than translucent with their colour
    /// raised against the black behind them (NeRF's random background).
    /// What the photographs see past the bounds is painted into the field
    /// the same way, so it suits captures whose rays all end inside the
    /// bounds: ROOM from its open side (the pixels seen through 3.9 % →
    /// 0.6 %), not DOG from its cap (45 % of the pixels with nothing in the
    /// bounds came out opaque; `docs/fidelity.md`, "Thirty-third pass").
    /// Needs opaque photographs (no pixel with alpha below 1).
    pub random_background: bool,
    /// A sky learnt with the field behind it instead of the fixed
    /// background ([`crate::field::sky`]): an equirect map of 2n × n texels, n
    /// this knob (0: the fixed background). What the photographs see past
    /// the bounds (a sky, a far wall) is then learnt as a function of
    /// direction rather than painted into the box or missed. Starts as the
    /// fixed background; where no training ray looks past the field it
    /// is filled from the nearest texels they saw ([`super::Sky::fill_unseen`]).
    /// 0 here: behind a capture that sees nothing past its bounds (the
    /// `render-views` sets) it takes up a faint glow of the light a thin
    /// field lets through, 0.5–1.5 dB of PSNR at the mean of their
    /// held-out views (`docs/benchmarks.md`, issue 25's sixteenth pass).
    /// `inlay train` chooses it from the views' light past the bounds
    /// unless told ([`super::past_bounds::LightPastBounds::auto_sky`]).
    pub sky: u32,
    /// Degree of the view-dependent colour trained (spherical harmonics,
    /// 0..=2; 0: one colour per node, as a bake's).
    pub sh_degree: u32,
    /// Share of all the steps, at the start of the first of several
    /// stages, trained at degree 1 where [`Self::sh_degree`] is 0; the
    /// coefficients are then dropped and the stage goes on at degree 0
    /// ([`Self::view_dependent_end`]). A wall lit on one face and dark on
    /// the other needs its nodes to show both faces from the first steps:
    /// at degree 0 the views from behind pull every node their rays reach
    /// dark, and the lit face forms in front of them (PLANTS' back wall,
    /// a dome up to 0.29 in front of its face). 0.1 by default (300 of
    /// 3000 steps): on the bundled scenes' `render-views` sets at 128
    /// nodes it raised 18 of the 20 held-out views and lowered one by
    /// 0.04 dB (PLANTS by up to 1.7 dB, its haze from 13–17 % of three
    /// views' light to 3–8 %); degree 1 through the whole first stage
    /// cost DOG and CUPS 0.5–1.8 dB (`docs/benchmarks.md`, issue 25's
    /// thirty-second pass). Its time: 15 s of DOG's 286 s default run on
    /// a 2-core AMD EPYC, where without it DOG's held-out views lost
    /// 0.2–0.6 dB and their depth error rose from 0.57–0.78 to 0.89–1.00
    /// node spacings (issue 25's forty-ninth pass). It ends with the
    /// first stage at the latest; 0: none.
    pub view_dependent_start: f64,
    /// Learn an RGB exposure gain per frame (the first frame's fixed at
    /// 1): for photographs whose exposure is not known. Held-out frames
    /// are scored at the gain that fits them best.
    pub learn_exposure: bool,
    /// After the last step, the density of every node whose largest
    /// rendering weight in any training ray is below this is set to zero
    /// ([`super::prune`]; not after Ctrl-C); 0 keeps every node. The default, 0.01, raised
    /// CUPS' held-out views by 0.2 dB and left DOG's within 0.2 dB
    /// (`docs/benchmarks.md`, "Pruning").
    pub prune: f64,
    /// Train the stages after the first only in the bricks of 8³ nodes
    /// around the surfaces the stage before made visible
    /// ([`super::sparse_stage`]); the rest held empty. A stage whose dense
    /// grid would not fit one storage binding is trained so always, a
    /// resumed field's only stage included (around what it makes visible).
    /// On by default since issue 25's nineteenth pass: DOG's last stage
    /// kept 667 of 2304 bricks, its steps over every node (Adam, total
    /// variation) took under a third of the time, and DOG's and ROOM's
    /// held-out views scored within 0.1 dB of the dense grid's
    /// (`docs/benchmarks.md`).
    pub sparse: bool,
    /// Each training ray passes through a point drawn uniformly over its
    /// pixel rather than through its centre, as a photograph's pixel
    /// gathered its light. Off by default: one such ray a pixel asks each
    /// point for the pixel's mean, which blurs a field whose nodes are
    /// finer than the pixels. On DOG's and PLANTS' Cycles sets (a pixel
    /// 2.3 node spacings across) the held-out views, scored over the
    /// pixels' area, read 32.1/31.6 and 29.6/29.7 dB with it against
    /// 33.9/34.0 and 30.1/29.9 without, and PLANTS' lamp lost an eighth of
    /// its light; CUPS moved by 0.05 dB (`docs/benchmarks.md`, issue 25's
    /// twenty-eighth pass).
    pub jitter: bool,
    /// Each training pixel is the mean of n × n rays through the centres
    /// of an even split of its area, and the loss is taken on that mean,
    /// as its photograph gathered the pixel's light (one ray a pixel asks
    /// the field for the pixel's mean along a line). A step keeps
    /// [`Self::batch`] rays, so it takes 1/n² as many pixels. 1..=
    /// [`MAX_AREA_RAYS`]; 1 by default. At 2, in the same time, the Cycles
    /// sets' held-out views read up to 1.8 dB higher (DOG 33.8/34.0 →
    /// 35.1/35.7 dB), but a haze gathers in front of the surfaces: on
    /// DOG's `render-views` set it hides 20 % of a view's surface light
    /// against 5 %, and the surfaces lie 1.4–2.2 node spacings off against
    /// 0.6–0.8. A pixel's rays share one gradient, and none is held to what
    /// it sees alone (`docs/benchmarks.md`, issue 25's twenty-ninth pass).
    pub area_rays: u32,
    /// Held-out views are rendered with n × n rays a pixel (stratified over
    /// its area) and averaged, as their photographs gathered the pixel's
    /// light; 1 renders the ray through each pixel's centre.
    pub held_out_samples: u32,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for TrainKnobs {
    fn default() -> Self {
        Self {
            resolution: 64,
            stages: 3,
            first_stage_share: 0.5,
            refine_density_exponent: 0.0,
            iterations: 3000,
            batch: 4096,
            samples_per_ray: 256,
            coarse_samples: 2.0,
            rate: 0.1,
            density_rate: 5.0,
            rate_decay: 0.1,
            epsilon: 4.0,
            scale: None,
            tv_colour: 0.0,
            tv_colour_edge: 1.0,
            tv_density: 3e-3,
            tv_edge: 0.1,
            sparsity: 1e-3,
            sparsity_edge: 0.03,
            distortion: 0.0,
            depth_weight: 1.0,
            depth_tolerance: 1.0,
            planes: true,
            random_background: false,
            sky: 0,
            sh_degree: 0,
            view_dependent_start: 0.1,
            learn_exposure: false,
            prune: 0.01,
            sparse: true,
            jitter: false,
            area_rays: 1,
            held_out_samples: DEFAULT_HELD_OUT_SAMPLES,
            seed: 1,
        }
    }
}

/// A total variation edge knob in its unit: `knob × unit` where the knob
/// is positive, else infinite (no edge: squared differences everywhere).
fn edge(knob: f64, unit: f64) -> f64 {
    if knob > 0.0 {
        knob * unit
    } else {
        f64::INFINITY
    }
}

/// Rays a pixel a held-out view is scored with, per axis
/// ([`TrainKnobs::held_out_samples`]). DOG's Cycles views of one field
/// read 31.59/30.73 dB at 1 (the centre ray), 33.54/33.77 at 2,
/// 33.85/33.99 at 4 and 33.88/33.97 at 8 (`docs/benchmarks.md`, issue
/// 25's twenty-eighth pass).
pub const DEFAULT_HELD_OUT_SAMPLES: u32 = 4;

/// The degree of the first stage's view-dependent start
/// ([`TrainKnobs::view_dependent_start`]).
pub const VIEW_DEPENDENT_START_DEGREE: u32 = 1;

/// A pixel wider than this many node spacings at the field's centre
/// takes [`AREA_RAYS_WIDE_PIXELS`] rays a side by default (`inlay train
/// --area-rays auto`, [`TrainKnobs::auto_area_rays`]). Measured on
/// photographs without alpha at 128 nodes: the five Cycles sets, whose 96
/// × 96 pixels span 2.15–2.42 spacings, read 0.06–3.05 dB higher on all
/// ten held-out views at 2 × 2 rays (ROOM 29.45/29.84 → 31.45/32.89, DOG
/// 33.83/34.24 → 35.30/36.34), their surfaces 0–0.23 spacings further
/// off; DOG's `render-views` set without alpha, whose 160 × 120 pixels
/// span 1.88, read the same (−0.31 to +0.23 dB) and its surfaces 0.14–0.43
/// spacings further off, with more haze (`docs/benchmarks.md`, issue
/// 25's thirty-ninth pass). Behind a random background 2 × 2 rays left a
/// haze on the surfaces (the twenty-ninth pass), so it takes none.
pub const WIDE_PIXEL_SPACINGS: f64 = 2.0;

/// The rays a side a wide pixel takes by default ([`WIDE_PIXEL_SPACINGS`]).
pub const AREA_RAYS_WIDE_PIXELS: u32 = 2;

/// The most rays a training pixel per axis [`TrainKnobs::area_rays`]
/// takes: its square is the trainer's most rays a pixel
/// ([`super::gpu::MAX_RAYS_PER_PIXEL`]).
pub const MAX_AREA_RAYS: u32 = 4;

/// The most rays a pixel per axis [`TrainKnobs::held_out_samples`] takes
/// (a 160 × 120 view at 16 × 16 a pixel marches 5 M rays on the CPU).
pub const MAX_HELD_OUT_SAMPLES: u32 = 16;

/// The fewest march samples along the diagonal a coarse stage takes
/// ([`TrainKnobs::stage_samples`]).
pub const MIN_STAGE_SAMPLES: u32 = 16;

/// The steps `inlay train` takes when not told: [`TrainKnobs::default`]'s
/// 3000 for a grid of up to 128 nodes along its longest axis (2000 before
/// the fourteenth pass of issue 25 in `docs/benchmarks.md`: with
/// [`TrainKnobs::tv_edge`] every bundled scene gained 0.6–1.6 dB and
/// depth, within 5 minutes), and
/// [`FINE_GRID_STEPS`] × (nodes / 128)² above, as the finest grid's nodes
/// grow per view (256 nodes: 8000). On DOG's 64 views of 256², 2000 steps
/// left a 256-node degree-1 field hazy where the training views never
/// looked through (held-out 27.75 and 31.47 dB); 8000 cleared it (31.60,
/// 30.74 dB) and 16 000 fitted the views' noise (31.03, 30.04 dB), while
/// a 128-node field with squared total variation gained nothing from 8000
/// (29.26, 31.84 against 29.24, 32.21 dB; issue 25's seventh pass).
pub fn default_iterations(resolution: u32) -> u32 {
    let r = resolution.clamp(FEW_STEPS_RESOLUTION, 512) as u64;
    let grown = FINE_GRID_STEPS as u64 * r * r
        / (FEW_STEPS_RESOLUTION as u64 * FEW_STEPS_RESOLUTION as u64);
    (grown as u32).max(TrainKnobs::default().iterations)
}

/// The share of [`default_iterations`] each run takes where a training
/// makes two ([`TrainKnobs::planes`]): on DOG's Cycles set two runs of
/// 2000 steps read 0.50 and 0.62 node spacings, 35.39 and 37.84 dB, in
/// 140 s, where two of 3000 read 0.37 and 0.46, 35.74 and 37.32 dB, in
/// twice one run's time (118 s), and one run of 3000 2.55 and 1.30,
/// 35.30 and 36.34 dB (`docs/benchmarks.md`, issue 25's forty-fourth
/// pass).
pub const TWO_RUN_SHARE: f64 = 2.0 / 3.0;

/// The steps of each of `runs` runs (1 or 2) when `inlay train` is not
/// told: [`default_iterations`], times [`TWO_RUN_SHARE`] for two.
pub fn default_run_iterations(resolution: u32, runs: u32) -> u32 {
    let all = default_iterations(resolution);
    if runs > 1 {
        (all as f64 * TWO_RUN_SHARE).round() as u32
    } else {
        all
    }
}

/// The steps of [`default_iterations`]' growth at 128 nodes, from which
/// grids above 128 nodes take four times as many per doubling.
pub const FINE_GRID_STEPS: u32 = 2000;

/// The refinement's exponent ([`TrainKnobs::refine_density_exponent`])
/// behind a random background. On the bundled scenes' `render-views` sets
/// (48 views of 160 × 120, 128 nodes, random background) it brought 12 of
/// the 20 held-out views within a node spacing of the recipe's surfaces
/// along the ray (9 at 0) and DOG, CUPS and BOOKS 0.3–0.4 dB, PLANTS −0.09
/// dB. Behind the fixed background of the opaque Cycles sets the trained
/// surfaces already stand in front of the recipe's, and 0.5 put them a
/// further 0.5–1.2 node spacings in front on DOG and CUPS for 0.0–0.2 dB
/// (`docs/benchmarks.md`, issue 25's twenty-fifth pass), so without a
/// random background the exponent stays 0.
pub const REFINE_EXPONENT_BEHIND_RANDOM: f64 = 0.5;

/// The sparsity prior's weight ([`TrainKnobs::sparsity`]) behind a random
/// background, where the refinement's exponent
/// ([`REFINE_EXPONENT_BEHIND_RANDOM`]) puts the surfaces in front of the
/// recipe's with a haze before them. On the bundled scenes' `render-views`
/// sets (48 views of 160 × 120, 128 nodes) it brought 15 of the 20
/// held-out views within a node spacing of the recipe's surfaces along the
/// ray (12 at 1e-3), 17 of them nearer, at the same held-out PSNR (the
/// scenes' means moved by −0.06 to +0.03 dB; `docs/benchmarks.md`, issue
/// 25's twenty-sixth pass).
pub const SPARSITY_BEHIND_RANDOM: f64 = 2e-3;

/// The sparsity prior's edge ([`TrainKnobs::sparsity_edge`]) behind a
/// random background, where the steeper refinement leaves a haze in front
/// of the surfaces up to about this density. On the `render-views` sets
/// an edge of 0.03 kept PLANTS' foliage whole (1.06 of its optical depth,
/// 0.46 at 0.1) but left that haze: 10 of the 20 held-out views within a
/// node spacing of the recipe's surfaces instead of 16, and 0.1–0.9 dB
/// less on PLANTS and DOG (`docs/benchmarks.md`, issue 25's thirty-third
/// pass).
pub const SPARSITY_EDGE_BEHIND_RANDOM: f64 = 0.1;

/// Up to this many nodes along the longest axis the default steps stay at
/// [`TrainKnobs::default`]'s.
pub const FEW_STEPS_RESOLUTION: u32 = 128;

impl TrainKnobs {
    /// The total variation's weights on a grid of node spacing `h`: the
    /// edge [`Self::tv_edge`] (an optical depth per spacing) as a density
    /// difference, τ/h; the colour's edge [`Self::tv_colour_edge`] times
    /// the radiance `scale`; the sparsity prior as a grid of `nodes` along
    /// its longest axis applies it ([`Self::sparsity_at`]).
    pub fn tv_weights(&self, h: f64, nodes: u32, scale: f64) -> super::tv::TvWeights {
        super::tv::TvWeights {
            colour: self.tv_colour,
            colour_edge: edge(self.tv_colour_edge, scale),
            density: self.tv_density,
            density_edge: edge(self.tv_edge, 1.0 / h),
            sparsity: self.sparsity_at(nodes),
            sparsity_edge: edge(self.sparsity_edge, 1.0 / h),
        }
    }

    /// The refinement's exponent to take where none is asked for:
    /// [`REFINE_EXPONENT_BEHIND_RANDOM`] behind a random background, else 0.
    pub fn auto_refine_exponent(&self) -> f64 {
        if self.random_background {
            REFINE_EXPONENT_BEHIND_RANDOM
        } else {
            0.0
        }
    }

    /// The rays a training pixel takes per axis where none are asked for,
    /// its pixels [`super::pixels::pixel_footprint`] node spacings wide:
    /// [`AREA_RAYS_WIDE_PIXELS`] where that is more than
    /// [`WIDE_PIXEL_SPACINGS`] and no random background goes behind the
    /// photographs, else 1.
    pub fn auto_area_rays(&self, footprint: f64) -> u32 {
        if footprint > WIDE_PIXEL_SPACINGS && !self.random_background {
            AREA_RAYS_WIDE_PIXELS
        } else {
            1
        }
    }

    /// The sparsity prior's weight to take where none is asked for:
    /// [`SPARSITY_BEHIND_RANDOM`] behind a random background, else
    /// [`TrainKnobs::default`]'s.
    pub fn auto_sparsity(&self) -> f64 {
        if self.random_background {
            SPARSITY_BEHIND_RANDOM
        } else {
            Self::default().sparsity
        }
    }

    /// The sparsity prior's edge to take where none is asked for:
    /// [`SPARSITY_EDGE_BEHIND_RANDOM`] behind a random background, else
    /// [`TrainKnobs::default`]'s.
    pub fn auto_sparsity_edge(&self) -> f64 {
        if self.random_background {
            SPARSITY_EDGE_BEHIND_RANDOM
        } else {
            Self::default().sparsity_edge
        }
    }

    /// The sparsity prior's weight as each step of a grid of `nodes` along
    /// its longest axis applies it: [`Self::sparsity`] up to
    /// [`FEW_STEPS_RESOLUTION`] nodes, × (128 / nodes)² above, as [`default_iterations`]
    /// grows the steps by (nodes / 128)². The prior pulls a faint density
    /// by the same share at every step, so over a default run a finer
    /// grid's pull then stays a 128-node run's, while each of its nodes
    /// is seen by fewer rays per step. Unscaled, 1e-3 at 256 nodes
    /// cleared DOG's surfaces: 4.8–33 % of their pixels seen through,
    /// held-out views 24–30 dB (`docs/benchmarks.md`, issue 25's
    /// eighteenth pass).
    pub fn sparsity_at(&self, nodes: u32) -> f64 {
        let r = nodes.max(FEW_STEPS_RESOLUTION) as f64;
        self.sparsity * (FEW_STEPS_RESOLUTION as f64 / r).powi(2)
    }

    /// The march's samples along the diagonal of a stage whose grid has
    /// `stage_nodes` along its longest axis where the final grid has
    /// `final_nodes`: [`Self::samples_per_ray`] scaled to
    /// [`Self::coarse_samples`] × the final grid's samples per node
    /// spacing (a coarse grid holds nothing fewer steps would miss),
    /// never below 16 or above the final grid's. Half of a default run's
    /// steps are on a grid a quarter as fine, which then marches half the
    /// samples (`docs/benchmarks.md`, issue 25's nineteenth pass).
    pub fn stage_samples(&self, stage_nodes: u32, final_nodes: u32) -> u32 {
        let share = self.coarse_samples * stage_nodes as f64 / final_nodes.max(1) as f64;
        let scaled = (self.samples_per_ray as f64 * share)
            .ceil()
            .min(u32::MAX as f64) as u32;
        scaled
            .max(self.samples_per_ray.min(MIN_STAGE_SAMPLES))
            .min(self.samples_per_ray)
    }

    /// The step at which stage `stage` (from 0) of `stages` ends: the
    /// first after [`Self::first_stage_share`] of the steps, the others at
    /// equal fractions of the rest, the last at [`Self::iterations`].
    pub fn stage_end(&self, stages: u32, stage: u32) -> u32 {
        let n = self.iterations as u64;
        if stages <= 1 || stage + 1 >= stages {
            return self.iterations;
        }
        let first = ((self.first_stage_share * n as f64).round() as u64).min(n);
        (first + (n - first) * stage as u64 / (stages as u64 - 1)) as u32
    }

    /// The stages a run takes: [`Self::stages`], one when it resumes a
    /// field (at the field's own resolution).
    pub fn stages_run(&self, resumed: bool) -> u32 {
        if resumed {
            1
        } else {
            self.stages
        }
    }

    /// The step at which the first stage's view-dependent start
    /// ([`Self::view_dependent_start`]) ends, of a run of `stages` stages
    /// (1 when resuming a field): None where there is none (one stage, a
    /// degree above 0, a share of 0 or one that rounds to no step).
    pub fn view_dependent_end(&self, stages: u32) -> Option<u32> {
        let steps = (self.view_dependent_start * self.iterations as f64).round() as u32;
        (stages > 1 && self.sh_degree == 0 && steps > 0)
            .then(|| steps.min(self.stage_end(stages, 0)))
    }

    /// The highest degree of view-dependent colour the run trains: 1 for
    /// the first stage's view-dependent start, else [`Self::sh_degree`].
    pub fn highest_sh_degree(&self, stages: u32) -> u32 {
        if self.view_dependent_end(stages).is_some() {
            VIEW_DEPENDENT_START_DEGREE
        } else {
            self.sh_degree
        }
    }

    /// Rays a training pixel is the mean of ([`Self::area_rays`] squared).
    pub fn rays_per_pixel(&self) -> u32 {
        self.area_rays.saturating_mul(self.area_rays)
    }

    /// How a training pixel's rays are drawn ([`Self::area_rays`],
    /// [`Self::jitter`]).
    pub fn pixel_rays(&self) -> super::pixels::PixelRays {
        super::pixels::PixelRays {
            area: self.area_rays,
            jitter: self.jitter,
        }
    }

    /// Pixels a step trains on: [`Self::batch`] rays, whole pixels of
    /// [`Self::rays_per_pixel`] rays.
    pub fn pixels_per_step(&self) -> u32 {
        self.batch / self.rays_per_pixel().max(1)
    }

    /// Why the knobs cannot be used: (knob, message).
    pub fn check(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if !(2..=512).contains(&self.resolution) {
            return bad(
                "resolution",
                format!("{} must be in 2..=512", self.resolution),
            );
        }
        if !(1..=6).contains(&self.stages) || self.resolution >> (self.stages - 1) < 2 {
            return bad(
                "stages",
                format!(
                    "{} stages from {} nodes leave fewer than 2 at the start",
                    self.stages, self.resolution
                ),
            );
        }
        if self.iterations == 0 || self.batch == 0 || !(4..=8192).contains(&self.samples_per_ray) {
            return bad(
                "iterations",
                "iterations and batch must be positive, samples_per_ray in 4..=8192".into(),
            );
        }
        if !(self.coarse_samples >= 1.0 && self.coarse_samples.is_finite()) {
            return bad(
                "coarse_samples",
                format!("{} must be at least 1", self.coarse_samples),
            );
        }
        if !(0.0..=1.0).contains(&self.refine_density_exponent) {
            return bad(
                "refine_density_exponent",
                format!("{} must lie between 0 and 1", self.refine_density_exponent),
            );
        }
        if !(self.first_stage_share > 0.0 && self.first_stage_share < 1.0) {
            return bad(
                "first_stage_share",
                format!("{} must lie between 0 and 1", self.first_stage_share),
            );
        }
        if !(0.0..=1.0).contains(&self.view_dependent_start) {
            return bad(
                "view_dependent_start",
                format!(
                    "{} must lie between 0 and 1 (a share of the steps)",
                    self.view_dependent_start
                ),
            );
        }
        if let Some(scale) = self.scale {
            if !(scale > 0.0 && scale.is_finite()) {
                return bad("scale", format!("{scale} must be a positive radiance"));
            }
        }
        if self.sky > crate::field::sky::MAX_SKY_HEIGHT {
            return bad(
                "sky",
                format!(
                    "{} must be in 0..={} (texels down)",
                    self.sky,
                    crate::field::sky::MAX_SKY_HEIGHT
                ),
            );
        }
        if self.sky > 0 && self.random_background {
            return bad(
                "sky",
                "a learnt sky and a random background both say what is behind the field: \
                 choose one"
                    .into(),
            );
        }
        if !(1..=MAX_AREA_RAYS).contains(&self.area_rays) || self.batch < self.rays_per_pixel() {
            return bad(
                "area_rays",
                format!(
                    "{} must be in 1..={MAX_AREA_RAYS} (rays a pixel per axis), and a step's {} \
                     rays must hold one pixel's {}",
                    self.area_rays,
                    self.batch,
                    self.rays_per_pixel()
                ),
            );
        }
        if !(1..=MAX_HELD_OUT_SAMPLES).contains(&self.held_out_samples) {
            return bad(
                "held_out_samples",
                format!(
                    "{} must be in 1..={MAX_HELD_OUT_SAMPLES} (rays a pixel per axis)",
                    self.held_out_samples
                ),
            );
        }
        if self.sh_degree > crate::field::MAX_SH_DEGREE {
            return bad(
                "sh_degree",
                format!(
                    "{} must be in 0..={}",
                    self.sh_degree,
                    crate::field::MAX_SH_DEGREE
                ),
            );
        }
        for (k, v) in [
            ("tv_colour", self.tv_colour),
            ("tv_colour_edge", self.tv_colour_edge),
            ("tv_density", self.tv_density),
            ("tv_edge", self.tv_edge),
            ("sparsity_edge", self.sparsity_edge),
            ("sparsity", self.sparsity),
            ("distortion", self.distortion),
            ("depth_weight", self.depth_weight),
            ("prune", self.prune),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, format!("{v} must be non-negative and finite"));
            }
        }
        // Total variation's plain step moves a node by up to 12 × its
        // weight × its differences: above 1/12 it overshoots and grows.
        for (k, v) in [
            ("tv_colour", self.tv_colour),
            ("tv_density", self.tv_density),
        ] {
            if v > super::tv::MAX_TV_WEIGHT {
                return bad(
                    k,
                    format!(
                        "{v} must be at most 1/12 ({:.4}): a larger step overshoots, and \
                         the values it smooths grow step after step",
                        super::tv::MAX_TV_WEIGHT
                    ),
                );
            }
        }
        for (k, v) in [
            ("rate", self.rate),
            ("density_rate", self.density_rate),
            ("rate_decay", self.rate_decay),
            ("epsilon", self.epsilon),
            ("depth_tolerance", self.depth_tolerance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, format!("{v} must be positive and finite"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sky past the largest size, or beside a random background (both
    /// say what is behind the field), is refused, naming the knob.
    #[test]
    fn a_sky_too_large_or_beside_a_random_background_is_refused() {
        let sky = |sky, random_background| TrainKnobs {
            sky,
            random_background,
            ..TrainKnobs::default()
        };
        assert!(sky(32, false).check().is_ok());
        assert!(sky(0, true).check().is_ok());
        assert_eq!(sky(32, true).check().unwrap_err().0, "sky");
        let big = crate::field::sky::MAX_SKY_HEIGHT + 1;
        assert_eq!(sky(big, false).check().unwrap_err().0, "sky");
    }

    /// Training rays a pixel outside 1..=4 per axis, or more than a step
    /// holds, are refused, naming the knob; a step keeps its rays and
    /// takes whole pixels of them.
    #[test]
    fn area_rays_outside_their_range_are_refused() {
        let knobs = |area_rays, batch| TrainKnobs {
            area_rays,
            batch,
            ..TrainKnobs::default()
        };
        assert_eq!(knobs(1, 4096).pixels_per_step(), 4096);
        assert_eq!(knobs(2, 4096).pixels_per_step(), 1024);
        assert_eq!(knobs(3, 4096).pixels_per_step(), 455);
        assert_eq!(knobs(3, 4096).rays_per_pixel(), 9);
        assert!(knobs(MAX_AREA_RAYS, 4096).check().is_ok());
        assert_eq!(
            MAX_AREA_RAYS * MAX_AREA_RAYS,
            crate::train::gpu::MAX_RAYS_PER_PIXEL
        );
        for (area, batch) in [(0, 4096), (MAX_AREA_RAYS + 1, 4096), (3, 8)] {
            assert_eq!(knobs(area, batch).check().unwrap_err().0, "area_rays");
        }
    }

    /// Held-out rays a pixel outside 1..=16 per axis are refused, naming
    /// the knob.
    #[test]
    fn held_out_samples_outside_their_range_are_refused() {
        let n = |held_out_samples| TrainKnobs {
            held_out_samples,
            ..TrainKnobs::default()
        };
        assert!(n(1).check().is_ok());
        assert!(n(MAX_HELD_OUT_SAMPLES).check().is_ok());
        for bad in [0, MAX_HELD_OUT_SAMPLES + 1] {
            assert_eq!(n(bad).check().unwrap_err().0, "held_out_samples");
        }
    }

    /// The depth loss's weight may be 0 (the maps ignored) but not
    /// negative or not a number; its tolerance must be positive and
    /// finite. Each is refused, naming the knob.
    #[test]
    fn depth_loss_knobs_outside_their_range_are_refused() {
        let k = |depth_weight, depth_tolerance| TrainKnobs {
            depth_weight,
            depth_tolerance,
            ..TrainKnobs::default()
        };
        assert!(k(0.0, 1.0).check().is_ok());
        assert!(k(3.0, 0.25).check().is_ok());
        for w in [-1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(k(w, 1.0).check().unwrap_err().0, "depth_weight");
        }
        for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(k(1.0, t).check().unwrap_err().0, "depth_tolerance");
        }
    }

    /// The edge is an optical depth per node spacing: on a grid twice as
    /// fine it is twice the density difference; 0 leaves the differences
    /// squared everywhere, and a negative edge is refused.
    /// Total variation above 1/12 is refused, and that is where its plain
    /// step turns unstable: a checkerboard of colour grows step after step
    /// just above it and fades just below.
    #[test]
    fn total_variation_beyond_its_stable_step_is_refused() {
        use super::super::tv::{tv_step, MAX_TV_WEIGHT};
        let res = glam::UVec3::splat(6);
        let amplitude = |w: f64| {
            let knobs = TrainKnobs {
                tv_colour: w,
                tv_colour_edge: 0.0,
                tv_density: 0.0,
                sparsity: 0.0,
                ..TrainKnobs::default()
            };
            let mut nodes: Vec<[f32; 4]> = (0..216)
                .map(|n| {
                    let (x, y, z) = (n % 6, (n / 6) % 6, n / 36);
                    let c = if (x + y + z) % 2 == 0 { 11.0 } else { 9.0 };
                    [c, c, c, 0.0]
                })
                .collect();
            for _ in 0..8 {
                tv_step(&mut nodes, res, knobs.tv_weights(0.1, 128, 1.0));
            }
            // An interior node and its neighbour.
            let (a, b) = (2 + 6 * (2 + 6 * 2), 3 + 6 * (2 + 6 * 2));
            (nodes[a][0] - nodes[b][0]).abs() / 2.0
        };
        assert!(amplitude(1.1 * MAX_TV_WEIGHT) > 2.0);
        assert!(amplitude(0.9 * MAX_TV_WEIGHT) < 1.0);
        for (k, w) in [("tv_colour", 0), ("tv_density", 1)] {
            let mut knobs = TrainKnobs::default();
            let set = |knobs: &mut TrainKnobs, v: f64| {
                if w == 0 {
                    knobs.tv_colour = v
                } else {
                    knobs.tv_density = v
                }
            };
            set(&mut knobs, MAX_TV_WEIGHT);
            assert!(knobs.check().is_ok());
            set(&mut knobs, 1e6);
            assert_eq!(knobs.check().unwrap_err().0, k);
        }
    }

    #[test]
    fn the_tv_edge_is_an_optical_depth_per_spacing() {
        let knobs = TrainKnobs {
            tv_edge: 0.02,
            ..TrainKnobs::default()
        };
        let tv = knobs.tv_weights(0.01, 128, 0.5);
        assert!((tv.density_edge - 2.0).abs() < 1e-12);
        assert_eq!(tv.density, knobs.tv_density);
        assert!((knobs.tv_weights(0.005, 128, 0.5).density_edge - 4.0).abs() < 1e-12);
        let off = TrainKnobs {
            tv_edge: 0.0,
            ..TrainKnobs::default()
        }
        .tv_weights(0.01, 128, 0.5);
        assert_eq!(off.density_edge_inverse(), 0.0);
        let bad = TrainKnobs {
            tv_edge: -1.0,
            ..TrainKnobs::default()
        };
        assert_eq!(bad.check().unwrap_err().0, "tv_edge");
        // The colour's edge is a share of the radiance scale.
        let colour = TrainKnobs {
            tv_colour_edge: 0.5,
            ..TrainKnobs::default()
        };
        assert!((colour.tv_weights(0.01, 128, 0.2).colour_edge - 0.1).abs() < 1e-12);
        let squared = TrainKnobs {
            tv_colour_edge: 0.0,
            ..TrainKnobs::default()
        };
        assert_eq!(
            squared.tv_weights(0.01, 128, 0.2).colour_edge_inverse(),
            0.0
        );
        let bad = TrainKnobs {
            tv_colour_edge: f64::NAN,
            ..TrainKnobs::default()
        };
        assert_eq!(bad.check().unwrap_err().0, "tv_colour_edge");
        // The sparsity prior's edge is an optical depth per spacing of its
        // own, apart from total variation's.
        let sparse = TrainKnobs {
            tv_edge: 0.1,
            sparsity_edge: 0.03,
            ..TrainKnobs::default()
        }
        .tv_weights(0.01, 128, 0.5);
        assert!((sparse.sparsity_edge - 3.0).abs() < 1e-12);
        assert!((sparse.density_edge - 10.0).abs() < 1e-12);
        let bad = TrainKnobs {
            sparsity_edge: f64::INFINITY,
            ..TrainKnobs::default()
        };
        assert_eq!(bad.check().unwrap_err().0, "sparsity_edge");
    }

    /// The sparsity prior reaches total variation's weights (as it is up
    /// to 128 nodes, falling as the square of the nodes above), so that
    /// sparsity alone still runs the step; a negative or infinite weight
    /// is refused.
    #[test]
    fn the_sparsity_prior_rides_on_total_variations_step() {
        let knobs = TrainKnobs {
            tv_density: 0.0,
            sparsity: 2e-3,
            ..TrainKnobs::default()
        };
        let tv = knobs.tv_weights(0.01, 128, 0.5);
        assert_eq!(tv.sparsity, 2e-3);
        assert!(!tv.is_none());
        // Stated for 128 nodes: as it is below, a quarter at 256.
        for (nodes, applied) in [(24, 2e-3), (128, 2e-3), (256, 5e-4), (512, 1.25e-4)] {
            assert!((knobs.tv_weights(0.01, nodes, 0.5).sparsity - applied).abs() < 1e-15);
            assert_eq!(
                knobs.sparsity_at(nodes),
                knobs.tv_weights(0.01, nodes, 0.5).sparsity
            );
        }
        for v in [-1e-3, f64::INFINITY] {
            let bad = TrainKnobs {
                sparsity: v,
                ..TrainKnobs::default()
            };
            assert_eq!(bad.check().unwrap_err().0, "sparsity");
        }
    }

    /// The view-dependent start takes its share of the steps at the
    /// start of the first of several stages, at most that stage, and only
    /// where the degree trained is 0; a share outside [0, 1] is refused.
    #[test]
    fn the_view_dependent_start_ends_within_the_first_stage() {
        let knobs = TrainKnobs {
            iterations: 3000,
            ..TrainKnobs::default()
        };
        assert_eq!(knobs.view_dependent_end(3), Some(300));
        assert_eq!(knobs.highest_sh_degree(3), VIEW_DEPENDENT_START_DEGREE);
        // A resumed field trains one stage: none.
        assert_eq!(knobs.stages_run(true), 1);
        assert_eq!(knobs.view_dependent_end(knobs.stages_run(true)), None);
        assert_eq!(knobs.highest_sh_degree(1), 0);
        let long = TrainKnobs {
            view_dependent_start: 0.9,
            ..knobs
        };
        assert_eq!(long.view_dependent_end(3), Some(1500));
        let dependent = TrainKnobs {
            sh_degree: 2,
            ..knobs
        };
        assert_eq!(dependent.view_dependent_end(3), None);
        assert_eq!(dependent.highest_sh_degree(3), 2);
        for share in [0.0, 1e-5] {
            let none = TrainKnobs {
                view_dependent_start: share,
                ..knobs
            };
            assert_eq!(none.view_dependent_end(3), None, "{share}");
            assert!(none.check().is_ok());
        }
        for share in [-0.1, 1.5, f64::NAN] {
            let bad = TrainKnobs {
                view_dependent_start: share,
                ..knobs
            };
            assert_eq!(bad.check().unwrap_err().0, "view_dependent_start");
        }
    }

    /// The first stage ends after its share of the steps, the others at
    /// equal fractions of the rest, the last at the final step; one stage
    /// takes every step; a share outside (0, 1) is refused.
    #[test]
    fn stages_end_after_their_shares_of_the_steps() {
        let knobs = TrainKnobs {
            iterations: 3000,
            ..TrainKnobs::default()
        };
        let ends: Vec<u32> = (0..3).map(|s| knobs.stage_end(3, s)).collect();
        assert_eq!(ends, [1500, 2250, 3000]);
        let four: Vec<u32> = (0..4).map(|s| knobs.stage_end(4, s)).collect();
        assert_eq!(four, [1500, 2000, 2500, 3000]);
        assert_eq!(knobs.stage_end(1, 0), 3000);
        let even = TrainKnobs {
            first_stage_share: 1.0 / 3.0,
            ..knobs
        };
        let ends: Vec<u32> = (0..3).map(|s| even.stage_end(3, s)).collect();
        assert_eq!(ends, [1000, 2000, 3000]);
        for share in [0.0, 1.0, f64::NAN] {
            let bad = TrainKnobs {
                first_stage_share: share,
                ..knobs
            };
            assert_eq!(bad.check().unwrap_err().0, "first_stage_share");
        }
    }

    /// Unasked, the sparsity prior is the default's behind a fixed
    /// background and stronger behind a random one, where the refinement
    /// leaves a haze in front of the surfaces.
    #[test]
    fn the_sparsity_prior_is_stronger_behind_a_random_background() {
        let fixed = TrainKnobs::default();
        assert_eq!(fixed.auto_sparsity(), fixed.sparsity);
        let random = TrainKnobs {
            random_background: true,
            ..fixed
        };
        assert_eq!(random.auto_sparsity(), SPARSITY_BEHIND_RANDOM);
        assert!(random.auto_sparsity() > fixed.auto_sparsity());
        // Its edge spares faint matter behind a fixed background; behind a
        // random one, whose refinement leaves more haze, it is total
        // variation's.
        assert_eq!(fixed.auto_sparsity_edge(), fixed.sparsity_edge);
        assert_eq!(random.auto_sparsity_edge(), SPARSITY_EDGE_BEHIND_RANDOM);
        assert!(fixed.auto_sparsity_edge() < random.auto_sparsity_edge());
        let chosen = TrainKnobs {
            sparsity: random.auto_sparsity(),
            ..random
        };
        assert!(chosen.check().is_ok());
    }

    /// The refinement's exponent lies between 0 (the field carried as it
    /// is) and 1 (each node's optical depth per spacing carried); unasked,
    /// it is 0.5 behind a random background and 0 behind a fixed one.
    #[test]
    fn the_refine_exponent_lies_between_0_and_1() {
        let fixed = TrainKnobs::default();
        assert_eq!(fixed.refine_density_exponent, 0.0);
        assert_eq!(fixed.auto_refine_exponent(), 0.0);
        let random = TrainKnobs {
            random_background: true,
            ..fixed
        };
        assert_eq!(random.auto_refine_exponent(), REFINE_EXPONENT_BEHIND_RANDOM);
        for p in [0.0, 0.5, 1.0] {
            let k = TrainKnobs {
                refine_density_exponent: p,
                ..TrainKnobs::default()
            };
            assert!(k.check().is_ok(), "{p}");
        }
        for p in [-0.1, 1.5, f64::NAN] {
            let bad = TrainKnobs {
                refine_density_exponent: p,
                ..TrainKnobs::default()
            };
            assert_eq!(bad.check().unwrap_err().0, "refine_density_exponent");
        }
    }

    /// A coarse stage takes the final grid's samples per node spacing
    /// (× the knob): a quarter of them on a grid a quarter as fine,
    /// rounded up, never below 16 (or the knob, where it is less) nor
    /// above the knob.
    #[test]
    fn coarse_stages_take_the_samples_per_spacing() {
        assert_eq!(TrainKnobs::default().coarse_samples, 2.0);
        let knobs = TrainKnobs {
            coarse_samples: 1.0,
            ..TrainKnobs::default()
        };
        assert_eq!(knobs.samples_per_ray, 256);
        assert_eq!(knobs.stage_samples(128, 128), 256);
        assert_eq!(knobs.stage_samples(64, 128), 128);
        assert_eq!(knobs.stage_samples(32, 128), 64);
        assert_eq!(knobs.stage_samples(33, 128), 66);
        assert_eq!(knobs.stage_samples(2, 128), 16);
        assert_eq!(knobs.stage_samples(200, 128), 256);
        let few = TrainKnobs {
            samples_per_ray: 10,
            ..knobs
        };
        assert_eq!(few.stage_samples(8, 128), 10);
        // Twice the final grid's samples per spacing; four times is every
        // stage at the knob.
        for (coarse_samples, stage, samples) in [(2.0, 32, 128), (2.0, 64, 256), (4.0, 32, 256)] {
            let k = TrainKnobs {
                coarse_samples,
                ..knobs
            };
            assert_eq!(k.stage_samples(stage, 128), samples);
        }
        for bad in [0.5, f64::NAN, f64::INFINITY] {
            let k = TrainKnobs {
                coarse_samples: bad,
                ..knobs
            };
            assert_eq!(k.check().unwrap_err().0, "coarse_samples");
        }
    }

    /// The default steps: 3000 up to 128 nodes, 2000 × (nodes/128)² above
    /// where that is more.
    #[test]
    fn default_steps_grow_with_the_grid() {
        assert_eq!(default_iterations(32), 3000);
        assert_eq!(default_iterations(128), 3000);
        assert_eq!(default_iterations(150), 3000);
        assert_eq!(default_iterations(192), 4500);
        assert_eq!(default_iterations(256), 8000);
        assert_eq!(default_iterations(512), 32000);
        assert_eq!(
            default_iterations(TrainKnobs::default().resolution),
            TrainKnobs::default().iterations
        );
    }
}
