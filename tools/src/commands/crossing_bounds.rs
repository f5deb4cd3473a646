//! The warning for a recipe whose surfaces reach past a field's bounds: a
//! field (and `inlay reference`, `inlay render-views`) holds only the part
//! inside, while Cycles (`tools/cycles/render_cycles.py`) draws all of it.

use std::path::Path;

use inlay_passes::geometry::Aabb;
use inlay_passes::scene::Recipe;

/// Prints a warning for each surface of `recipe` (read from `scene`) that
/// crosses `bounds` (`whose` names them: "the recipe's", "the dataset's"),
/// with how far it reaches past them.
pub fn warn_crossing_bounds(scene: &Path, recipe: &Recipe, bounds: Aabb, whose: &str) {
    for (p, past) in recipe.crossing(bounds) {
        eprintln!(
            "warning: {}: `{}` reaches {past:.3} past {whose} bounds: a field holds only the part \
             inside (as `inlay reference` and `render-views` draw it), so photographs of the \
             whole primitive (Cycles') show what no field in these bounds can",
            scene.display(),
            p.name
        );
    }
}
