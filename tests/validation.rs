//! The validation layer is really on in tests, and an error it reports fails
//! the run.

mod common;

#[test]
fn a_validation_error_is_caught_and_fails() {
    let ctx = common::gpu();
    assert!(ctx.validating());
    common::assert_no_validation_errors(&ctx);
    ctx.provoke_validation_error();
    let err = ctx
        .check_validation()
        .expect_err("a buffer of size 0 must be reported by the layer");
    let text = err.to_string();
    assert!(text.contains("VUID-VkBufferCreateInfo-size"), "{text}");
    // Once reported, the errors are consumed.
    common::assert_no_validation_errors(&ctx);
    // And the assertion used by every GPU test panics on it.
    ctx.provoke_validation_error();
    let panicked = std::panic::catch_unwind(|| common::assert_no_validation_errors(&ctx));
    assert!(panicked.is_err());
}
