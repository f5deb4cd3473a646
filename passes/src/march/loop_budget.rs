//! Loop budgets. Mesa's llvmpipe (lavapipe, the development and CI device)
//! ends every loop of a shader invocation once 65535 iterations of all
//! its loops together have run, then carries on after them: a kernel
//! whose invocation marches too many samples returns a wrong image with
//! no error ([`inlay_engine::DeviceInfo::loop_iteration_limit`]). A pass
//! whose invocations loop over rays therefore either splits its rays so
//! that each invocation stays under the device's limit
//! ([`items_per_invocation`]), or refuses its knobs before anything runs
//! ([`check_loop_budget`]), naming them.

use inlay_engine::Context;

/// How many of `wanted` items, each up to `per_item` loop iterations,
/// one invocation may take beside `fixed` iterations of its own under
/// `limit` (None: no limit, all of them); None when even one item is over
/// it.
pub fn items_per_invocation(
    limit: Option<u64>,
    fixed: u64,
    per_item: u64,
    wanted: u32,
) -> Option<u32> {
    let Some(limit) = limit else {
        return Some(wanted.max(1));
    };
    let room = limit.checked_sub(fixed)? / per_item.max(1);
    (room >= 1).then(|| room.min(wanted.max(1) as u64) as u32)
}

/// Refuses kernel `kernel` when one of its invocations may run more
/// `iterations` (all its loops together) than `ctx`'s device lets it;
/// `knobs` names what set them, for the message.
pub fn check_loop_budget(
    ctx: &Context,
    kernel: &str,
    iterations: u64,
    knobs: impl FnOnce() -> String,
) -> anyhow::Result<()> {
    match ctx.info().loop_iteration_limit {
        Some(limit) if iterations > limit => anyhow::bail!(
            "{kernel}: one invocation may loop {iterations} times ({}), but {} stops an \
             invocation's loops after {limit} and would cut its rays short without an error; \
             lower those knobs",
            knobs(),
            ctx.info().name
        ),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_fill_the_budget_and_no_more() {
        assert_eq!(items_per_invocation(None, 10, 1000, 36), Some(36));
        assert_eq!(items_per_invocation(Some(65535), 0, 514, 36), Some(36));
        // 256 rays of 1026 iterations: 63 fit in 65535 − 100.
        assert_eq!(items_per_invocation(Some(65535), 100, 1026, 256), Some(63));
        assert_eq!(items_per_invocation(Some(65535), 0, 70000, 4), None);
        assert_eq!(items_per_invocation(Some(50), 60, 1, 4), None);
        assert_eq!(items_per_invocation(Some(65535), 0, 0, 0), Some(1));
    }
}
