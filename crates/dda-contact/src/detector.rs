//! The [`ContactDetector`] trait and the two drivers every detector shares: step-start
//! detection over all neighbour pairs with state inheritance ([`detect`]), and the
//! open-close-iteration update from trial displacements ([`track`]).

use crate::contact::{Contact, ContactKey, ContactSet, ContactState, PairContacts};
use crate::cover::CoverDetector;
use crate::neighbour::NeighbourPair;
use crate::shape::BlockShape;
use crate::territory::TerritoryDetector;
use dda_geom::{DVec2, Motion, VertexEdge};
use std::fmt;

/// Tolerances of detection (paper section 2.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectionParams {
    /// Contact tolerance d_tol (the paper's d_n^tol), m: radius of an edge's contact region.
    pub d_tol: f64,
    /// Entrance angle tolerance theta_e (the paper's theta_e^tol), radians.
    theta_e: f64,
    /// sin(theta_e), computed once: the filters use it for every vertex-edge pair.
    sin_theta_e: f64,
}

impl DetectionParams {
    /// Tolerances for a step limited to rotation `theta_max`: theta_e = 2 theta_max
    /// (paper section 2.6).
    pub fn new(d_tol: f64, theta_max: f64) -> Self {
        let theta_e = 2.0 * theta_max;
        DetectionParams {
            d_tol,
            theta_e,
            sin_theta_e: theta_e.sin(),
        }
    }

    /// The same tolerances with contact tolerance `d_tol`.
    pub(crate) fn with_d_tol(self, d_tol: f64) -> Self {
        DetectionParams { d_tol, ..self }
    }

    /// The entrance angle tolerance theta_e, radians.
    #[inline]
    pub fn theta_e(&self) -> f64 {
        self.theta_e
    }

    /// sin(theta_e), the bound of the entrance filter (paper eq. 5-6).
    #[inline]
    pub fn sin_theta_e(&self) -> f64 {
        self.sin_theta_e
    }
}

/// A contact detector: finds the candidate contacts of a neighbour pair and their initial
/// activity at step start, and optionally activates candidates during open-close iteration
/// from the trial motion. Object-safe, so an engine holds a `Box<dyn ContactDetector>`
/// chosen at run time, and other crates can add their own.
pub trait ContactDetector: Send + Sync + fmt::Debug {
    /// The name a scene's `detector` key uses.
    fn name(&self) -> &str;

    /// Appends the candidate contacts of the pair of blocks `ids` (shapes `a` = block
    /// `ids.a`, `b` = block `ids.b`) to `out`, each with its initial activity and with the
    /// state [`Contact::new`] gives; the driver sorts them and inherits states.
    fn detect_pair(
        &self,
        a: &BlockShape,
        b: &BlockShape,
        ids: NeighbourPair,
        params: &DetectionParams,
        out: &mut Vec<Contact>,
    );

    /// Whether [`Self::activates`] should be asked during open-close iteration.
    fn tracks_trajectories(&self) -> bool {
        false
    }

    /// Whether a contact closed at the end of the previous step stays a candidate while its
    /// vertex is behind the edge's line, however deep (beyond d_tol, where the distance
    /// filter would drop it), moved to the adjacent edge when the vertex slides past an
    /// end of its edge.
    fn keeps_closed_contacts(&self) -> bool {
        false
    }

    /// Whether a corner contact locked at the end of the previous step keeps its spring
    /// against its twin, the other block's corner there (`keep_corners` in this module).
    fn keeps_corners(&self) -> bool {
        false
    }

    /// Whether an inactive candidate becomes active, given its measures at step start and
    /// after the trial displacement. Asked only when the vertex was outside the edge's line
    /// at step start and is behind it in the trial (d_n0 > 0 > d_n1, the trigger of
    /// trajectory tracking, paper 2.3.2): [`track`] skips every other candidate unmeasured.
    fn activates(&self, _start: VertexEdge, _trial: VertexEdge) -> bool {
        false
    }
}

/// Names of the built-in detectors, as a scene's `detector` key spells them.
pub const DETECTOR_NAMES: [&str; 3] = ["cover", "type-1", "type-2"];

/// A detector name that is not one of [`DETECTOR_NAMES`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownDetector(pub String);

impl fmt::Display for UnknownDetector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown detector `{}` (expected one of: {})",
            self.0,
            DETECTOR_NAMES.join(", ")
        )
    }
}

impl std::error::Error for UnknownDetector {}

/// The built-in detector called `name`.
pub fn detector_by_name(name: &str) -> Result<Box<dyn ContactDetector>, UnknownDetector> {
    match name {
        "cover" => Ok(Box::new(CoverDetector)),
        "type-1" => Ok(Box::new(TerritoryDetector::type1())),
        "type-2" => Ok(Box::new(TerritoryDetector::type2())),
        other => Err(UnknownDetector(other.to_string())),
    }
}

/// Detects the candidates of `pairs` into `list` and `ranges` (offsets into `list`).
fn detect_range(
    detector: &dyn ContactDetector,
    shapes: &[BlockShape],
    pairs: &[NeighbourPair],
    params: &DetectionParams,
    previous: &ContactSet,
    list: &mut Vec<Contact>,
    ranges: &mut Vec<PairContacts>,
) {
    // Both pair lists are sorted: walk the previous one with a cursor.
    let mut prev_k = match pairs.first() {
        Some(first) => previous.pairs.partition_point(|p| p.pair < *first),
        None => 0,
    };
    for &pair in pairs {
        let start = list.len();
        detector.detect_pair(
            &shapes[pair.a as usize],
            &shapes[pair.b as usize],
            pair,
            params,
            list,
        );
        while prev_k < previous.pairs.len() && previous.pairs[prev_k].pair < pair {
            prev_k += 1;
        }
        let before = match previous.pairs.get(prev_k) {
            Some(p) if p.pair == pair => previous.of_pair(prev_k),
            _ => &[],
        };
        let mut deep = false;
        if detector.keeps_closed_contacts()
            && before.iter().any(|c| c.active && c.state.is_closed())
        {
            deep = crate::cover::deep_covers(
                &shapes[pair.a as usize],
                &shapes[pair.b as usize],
                pair,
                params,
                before,
                start,
                list,
            );
            if !deep {
                keep_closed(shapes, pair, params, before, start, list);
            }
        } else {
            keep_bonded(shapes, params.d_tol, before, start, list);
        }
        if detector.keeps_corners() && !deep {
            keep_corners(shapes, params, before, &mut list[start..]);
        }
        if list.len() == start {
            continue;
        }
        let mine = &mut list[start..];
        mine.sort_unstable_by_key(|c| c.key);
        // Inherit the closed state (locked or sliding), the locked point and the cohesion
        // of the same vertex-edge pair at the end of the previous step (paper 2.3.1).
        let mut j = 0;
        for c in mine.iter_mut() {
            // Both lists are sorted by key: walk them together.
            while j < before.len() && before[j].key < c.key {
                j += 1;
            }
            if let Some(old) = before.get(j).filter(|o| o.key == c.key) {
                c.bonded = old.bonded;
                if old.active && old.state.is_closed() {
                    c.state = old.state;
                    c.locked_r = old.locked_r;
                    c.slide_dir = old.slide_dir;
                    c.normal_force = old.normal_force;
                }
            }
        }
        ranges.push(PairContacts {
            pair,
            start: start as u32,
            end: list.len() as u32,
            deep,
        });
    }
}

/// Appends, as active candidates, the bonded contacts closed at the end of the previous
/// step (`before`) that a detector without [`ContactDetector::keeps_closed_contacts`] did
/// not list (those at `list[start..]`), while the vertex lies within `d_tol` of its edge's
/// line and along the edge to within `d_tol` past an end: a bond (the glue between parts
/// of one body, a cohesive joint) holds until the contact law breaks it, not until a
/// detector's local choice at a corner drops it. The type-based detectors choose one of
/// a seam end's two corners afresh each step, and their rule that a vertex outside the
/// other block has no contact behind a line drops the other; the glue there went with
/// it, and a glued sliver part sank through its body (docs/method.md section 5).
fn keep_bonded(
    shapes: &[BlockShape],
    d_tol: f64,
    before: &[Contact],
    start: usize,
    list: &mut Vec<Contact>,
) {
    let listed = list.len();
    for old in before
        .iter()
        .filter(|o| o.active && o.bonded && o.state.is_closed())
    {
        let k = old.key;
        if list[start..listed].iter().any(|c| c.key == k) {
            continue;
        }
        let (vs, es) = (
            &shapes[k.vertex_block as usize],
            &shapes[k.edge_block as usize],
        );
        let e = k.edge as usize;
        let (p0, p1) = (es.vertices[e], es.vertices[es.next(e)]);
        let m = VertexEdge::new(vs.vertices[k.vertex as usize], p0, p1);
        let past = d_tol / p0.distance(p1);
        if m.d_n.abs() <= d_tol && (-past..=1.0 + past).contains(&m.r) {
            list.push(Contact::new(k, m.d_n, m.r, true));
        }
    }
}

/// Whether directions `a` and `b` are parallel within theta_e (`sin_e` its sine) and point
/// the same way: two faces of the entrance block that are one face (eq. 11's companions),
/// or, with one of them reversed, two edges that run along each other (a flush joint).
pub(crate) fn quasi_parallel(a: DVec2, b: DVec2, sin_e: f64) -> bool {
    a.dot(b) > 0.0 && a.perp_dot(b).abs() <= sin_e
}

/// How near, as a fraction of d_tol, a vertex must be to a corner of the other block for
/// their two contacts to be one corner's ([`keep_corners`]). Our choice: a thousandth of
/// d_tol, 2e-6 m in the grids of [`keep_corners`], twenty-five times the 8e-8 m a step
/// they hopped by; a spring on its edge's line that far past the edge's end is where the
/// corner is, to that much.
pub(crate) const CORNER_SLACK: f64 = 1e-3;

/// A locked corner keeps its spring where two blocks' corners meet along a flush joint (a
/// grid's X-junctions, the head joints of a wall, equal blocks stacked), among the pair's
/// candidates `mine`. A vertex V of one block within [`CORNER_SLACK`] of a corner C of
/// the other, against the edge that ends at C, and C against V's edge along that edge
/// (anti-parallel within theta_e) are one corner contact carried by either block: twins.
/// The cover detector makes active the twins with r in [0, 1]: both where the corners
/// coincide to rounding, else one or the other by the sign of the corners' offset along
/// the joint, a hair either way, which can flip from step to step; TB-CD-2 chooses among
/// a corner's contacts afresh each step, by territories the same hair decides. A corner
/// whose spring moves from one block's vertex to the other's, or from two springs to one,
/// changes its stiffness and the blocks' equilibrium, and the blocks hop between the
/// equilibria: 8 x 8 grids of equal blocks between two walls, friction 5 and 30 degrees,
/// still moved at 8e-5 m/s after 0.5 s (TB-CD-2: 4e-5 m/s), the twins at the X-junctions
/// of their middle joint changing at every step. So, for a detector that
/// [`ContactDetector::keeps_corners`], where one twin was locked at the end of the
/// previous step and the other was not, the locked one stays active while its vertex is
/// behind its edge's line (d_n < 0), within [`CORNER_SLACK`] of the corner, and its twin
/// is not (our choice). Sliding contacts are left to the detector: a block sliding past a
/// corner moves the contact from twin to twin as it goes, and held back there a block
/// sliding down a jointed slope while the mass settled flickered and never came steady (a
/// generated mass of 127 blocks: 1,331 static steps, unconverged, against 158).
/// Frictionless contacts slide, so a frictionless grid between walls still hops
/// (`docs/method.md` section 5).
fn keep_corners(
    shapes: &[BlockShape],
    params: &DetectionParams,
    before: &[Contact],
    mine: &mut [Contact],
) {
    let slack = CORNER_SLACK * params.d_tol;
    let sin_e = params.sin_theta_e();
    // `before` is sorted by key (see `detect_range`).
    let locked_before = |key: ContactKey| {
        before
            .binary_search_by_key(&key, |o| o.key)
            .is_ok_and(|i| before[i].active && before[i].state == ContactState::Locked)
    };
    for i in 0..mine.len() {
        let k = mine[i].key;
        let (vs, es) = (
            &shapes[k.vertex_block as usize],
            &shapes[k.edge_block as usize],
        );
        let (v, e) = (k.vertex as usize, k.edge as usize);
        let at = vs.vertices[v];
        // The corner of the edge V is at, and V's edge along the joint from there:
        // running back over the edge from V where V is at its end, into V at its start.
        let (corner, along) = if at.distance(es.vertices[es.next(e)]) <= slack {
            (es.next(e), v)
        } else if at.distance(es.vertices[e]) <= slack {
            (e, vs.prev(v))
        } else {
            continue;
        };
        if !quasi_parallel(es.tangents[e], -vs.tangents[along], sin_e) {
            continue;
        }
        let twin = ContactKey {
            vertex_block: k.edge_block,
            vertex: corner as u32,
            edge_block: k.vertex_block,
            edge: along as u32,
        };
        // Each pair of twins once, from the first by key.
        if twin < k {
            continue;
        }
        let Some(j) = mine.iter().position(|c| c.key == twin) else {
            continue;
        };
        let held = |c: &Contact| locked_before(c.key) && (c.active || c.d_n < 0.0);
        let (ha, hb) = (held(&mine[i]), held(&mine[j]));
        if ha != hb {
            mine[i].active = ha;
            mine[j].active = hb;
        }
    }
}

/// Appends, as active candidates, the contacts closed at the end of the previous step
/// (`before`, sorted) that the detector did not list (those at `list[start..]`) but whose
/// vertex is still behind its edge's line (d_n < 0): a penetration deeper than d_tol,
/// which a small penalty allows, must keep pushing the blocks apart rather than let them
/// pass through each other. A vertex that slid past an end of its edge (r outside
/// [0, 1]) has its contact moved to the adjacent edge on that side while that edge's line
/// is nearer (the walk repeats along the boundary, and ends outside the block if the
/// vertex has left it over an end): the move never lengthens the spring, so it stores no
/// energy, and the contact stays on the face the vertex entered rather than jump to the
/// block's far side (a vertex deep in a thin plate is nearer the far face, and a spring
/// to it pushes the vertex through). One the detector listed but did not choose is made
/// active again while its vertex is behind its edge's line within it only where the
/// detector chose no cover of the pair, where it carries a bond, or where it lies on a
/// face the detector chose (quasi-parallel to a chosen cover, as a companion of eq. 11
/// is). Where the detector chose another face, that face of the entrance block is the
/// vertex's shortest exit (eq. 11), and a second spring is a strut: two blocks that meet
/// only corner to corner where four meet (written flush, or pressed together) overlap by
/// the joints' own compression, each corner behind both faces of the other, and kept
/// closed on both, the deeper face's spring held a column of four blocks standing 4
/// degrees beyond its toppling limit. On a chosen face, "within" is to
/// [`crate::cover::ROUNDING`]: where two blocks' corners meet at a flush joint's end, each
/// lies on the other's edge at its end, r = 0 or 1 to rounding, and both covers of one
/// end could lie 2e-15 outside their edges, so that the joint kept its springs at its
/// other end only: a block resting across the joint of two others rocked them at 6e-6
/// m/s for ever, the springs at alternate ends from step to step (docs/method.md section
/// 5). States are inherited after, where the key is the same.
fn keep_closed(
    shapes: &[BlockShape],
    pair: NeighbourPair,
    params: &DetectionParams,
    before: &[Contact],
    start: usize,
    list: &mut Vec<Contact>,
) {
    let listed = list.len();
    let (a, b) = (&shapes[pair.a as usize], &shapes[pair.b as usize]);
    // The faces of the entrance block the detector chose, before any is kept here (a
    // pair has a few; beyond the eighth none is kept on account of it, which errs
    // towards fewer springs).
    let mut chosen = [DVec2::ZERO; 8];
    let mut n_chosen = 0;
    for c in list[start..listed].iter().filter(|c| c.active) {
        if n_chosen < chosen.len() {
            chosen[n_chosen] = crate::cover::face_direction(c, pair, a, b);
            n_chosen += 1;
        }
    }
    let sin_e = params.sin_theta_e();
    for old in before.iter().filter(|o| o.active && o.state.is_closed()) {
        let k = old.key;
        if let Some(c) = list[start..listed].iter_mut().find(|c| c.key == k) {
            // Listed but not chosen: kept where the detector chose nothing, where it
            // carries a bond, or where it lies on a face the detector chose (it is then
            // off its edge's end by rounding at most); a closed cover on another face
            // would be a strut beside the vertex's shortest exit.
            let es = &shapes[k.edge_block as usize];
            let end = crate::cover::ROUNDING * params.d_tol / es.lengths[k.edge as usize];
            let d = crate::cover::face_direction(c, pair, a, b);
            let on_chosen = chosen[..n_chosen]
                .iter()
                .any(|&m| quasi_parallel(d, m, sin_e));
            if c.d_n < 0.0
                && (-end..=1.0 + end).contains(&c.r)
                && (n_chosen == 0 || old.bonded || on_chosen)
            {
                c.active = true;
            }
            continue;
        }
        let (vs, es) = (
            &shapes[k.vertex_block as usize],
            &shapes[k.edge_block as usize],
        );
        let a = vs.vertices[k.vertex as usize];
        let measure = |j: usize| VertexEdge::new(a, es.vertices[j], es.vertices[es.next(j)]);
        let (mut j, mut m) = (k.edge as usize, measure(k.edge as usize));
        for _ in 0..es.len() {
            let side = if m.r < 0.0 {
                es.prev(j)
            } else if m.r > 1.0 {
                es.next(j)
            } else {
                break;
            };
            let n = measure(side);
            if n.d_n <= m.d_n {
                break;
            }
            (j, m) = (side, n);
        }
        let key = ContactKey {
            edge: j as u32,
            ..k
        };
        if m.d_n >= 0.0 || list[start..].iter().any(|c| c.key == key) {
            continue;
        }
        list.push(Contact::new(key, m.d_n, m.r, true));
    }
}

/// Step-start detection: the candidates of every neighbour pair (which must be sorted),
/// with initial activity from the detector and closed states inherited from `previous`
/// where the same vertex-edge pair was active and closed. `out` is overwritten. With the
/// `rayon` feature and `parallel`, pairs are split into chunks detected on the thread
/// pool and joined in order, so the result is identical to the sequential run.
pub fn detect(
    detector: &dyn ContactDetector,
    shapes: &[BlockShape],
    pairs: &[NeighbourPair],
    params: &DetectionParams,
    previous: &ContactSet,
    parallel: bool,
    out: &mut ContactSet,
) {
    out.clear();
    #[cfg(feature = "rayon")]
    if parallel && pairs.len() >= 256 {
        use rayon::prelude::*;
        let chunk = pairs.len().div_ceil(rayon::current_num_threads().max(1));
        let parts: Vec<(Vec<Contact>, Vec<PairContacts>)> = pairs
            .par_chunks(chunk)
            .map(|ps| {
                let (mut list, mut ranges) = (Vec::new(), Vec::new());
                detect_range(
                    detector,
                    shapes,
                    ps,
                    params,
                    previous,
                    &mut list,
                    &mut ranges,
                );
                (list, ranges)
            })
            .collect();
        for (list, ranges) in parts {
            let base = out.contacts.len() as u32;
            out.contacts.extend_from_slice(&list);
            out.pairs.extend(ranges.into_iter().map(|r| PairContacts {
                start: r.start + base,
                end: r.end + base,
                ..r
            }));
        }
        return;
    }
    let _ = parallel;
    detect_range(
        detector,
        shapes,
        pairs,
        params,
        previous,
        &mut out.contacts,
        &mut out.pairs,
    );
}

/// The vertex and the edge's two ends of contact `key` at the trial positions (block i
/// moved by `trial[i]`).
#[inline]
pub(crate) fn trial_points(
    shapes: &[BlockShape],
    trial: &[Motion],
    key: ContactKey,
) -> (DVec2, DVec2, DVec2) {
    let (vs, es) = (
        &shapes[key.vertex_block as usize],
        &shapes[key.edge_block as usize],
    );
    let (mv, me) = (
        &trial[key.vertex_block as usize],
        &trial[key.edge_block as usize],
    );
    let j = key.edge as usize;
    (
        mv.apply(vs.vertices[key.vertex as usize]),
        me.apply(es.vertices[j]),
        me.apply(es.vertices[es.next(j)]),
    )
}

/// Open-close iteration update of activity: every inactive candidate is measured at the
/// trial positions (block i moved by `trial[i]`, its motion about its centroid, rotation
/// exact) and activated, closed and locked where its trajectory
/// crossed the edge, when the detector says so. Returns how many became active.
pub fn track(
    detector: &dyn ContactDetector,
    shapes: &[BlockShape],
    trial: &[Motion],
    set: &mut ContactSet,
) -> usize {
    let mut list = TrackList::new();
    list.rebuild(detector, shapes, set);
    list.track(detector, shapes, trial, set)
}

/// The candidates trajectory tracking may activate in one step, with their vertex and
/// edge ends at step start copied beside them: the open-close iteration then reads one
/// array in order instead of every candidate's two block shapes (loads that miss the
/// cache), and computes the same trial positions from the same numbers.
#[derive(Clone, Debug, Default)]
pub struct TrackList {
    entries: Vec<Tracked>,
    /// The candidates the last [`TrackList::track`] made active, in the order it did.
    activated: Vec<u32>,
}

/// One entry of a [`TrackList`].
#[derive(Clone, Copy, Debug)]
struct Tracked {
    /// Index of the candidate in the step's [`ContactSet`].
    contact: u32,
    /// Its vertex block and edge block.
    blocks: [u32; 2],
    /// Its vertex and its edge's two ends at step start.
    points: [DVec2; 3],
}

impl TrackList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// Lists the candidates of `set` (as detected at step start) that tracking may
    /// activate: inactive, with the vertex outside the edge's line (d_n0 > 0, the trigger
    /// of paper 2.3.2). Within a step no other candidate can meet the trigger: d_n0 is
    /// fixed, and the open-close iteration only activates candidates, or moves a closed
    /// spring between those behind their edge's line (d_n0 <= 0).
    pub fn rebuild(
        &mut self,
        detector: &dyn ContactDetector,
        shapes: &[BlockShape],
        set: &ContactSet,
    ) {
        self.entries.clear();
        if !detector.tracks_trajectories() {
            return;
        }
        for (k, c) in set.contacts.iter().enumerate() {
            if c.active || c.d_n <= 0.0 {
                continue;
            }
            let key = c.key;
            let (vs, es) = (
                &shapes[key.vertex_block as usize],
                &shapes[key.edge_block as usize],
            );
            let j = key.edge as usize;
            self.entries.push(Tracked {
                contact: k as u32,
                blocks: [key.vertex_block, key.edge_block],
                points: [
                    vs.vertices[key.vertex as usize],
                    es.vertices[j],
                    es.vertices[es.next(j)],
                ],
            });
        }
    }

    /// Open-close iteration update of activity for the set the list was built from (see
    /// [`track`]). Returns how many candidates became active (listed by
    /// [`TrackList::activated`]).
    pub fn track(
        &mut self,
        detector: &dyn ContactDetector,
        shapes: &[BlockShape],
        trial: &[Motion],
        set: &mut ContactSet,
    ) -> usize {
        self.activated.clear();
        if !detector.tracks_trajectories() {
            return 0;
        }
        let mut changed = 0;
        for t in &self.entries {
            let c = &mut set.contacts[t.contact as usize];
            if c.active {
                continue;
            }
            let (mv, me) = (&trial[t.blocks[0] as usize], &trial[t.blocks[1] as usize]);
            let [a, b0, b1] = t.points;
            let (a1, b0, b1) = (mv.apply(a), me.apply(b0), me.apply(b1));
            // The trigger: behind the edge's line in the trial (the sign of d_n1).
            let (e, w) = (b1 - b0, a1 - b0);
            if w.x * e.y - w.y * e.x >= 0.0 {
                continue;
            }
            let trial_m = VertexEdge::new(a1, b0, b1);
            if detector.activates(VertexEdge { d_n: c.d_n, r: c.r }, trial_m) {
                // Lock where the trajectory crossed the edge's line (0 <= t <= 1).
                let at = c.d_n / (c.d_n - trial_m.d_n);
                c.active = true;
                c.state = crate::contact::ContactState::Locked;
                c.locked_r = (c.r + at * (trial_m.r - c.r)).clamp(0.0, 1.0);
                self.activated.push(t.contact);
                changed += 1;
            }
        }
        if detector.keeps_closed_contacts() {
            changed += crate::cover::follow_deepest(shapes, trial, set, &mut self.activated);
        }
        changed
    }

    /// The candidates the last [`TrackList::track`] made active (a spring moved to the
    /// deepest face included), each once, in the order it did.
    pub fn activated(&self) -> &[u32] {
        &self.activated
    }
}
