//! The `pbgi` binary as a shell runs it.

use std::process::{Command, Stdio};

#[test]
fn a_reader_that_closes_the_pipe_ends_pbgi_without_a_panic() {
    // `pbgi scenes | head -0`: the pipe's read end is closed before pbgi
    // writes its first line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_pbgi"))
        .arg("scenes")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pbgi starts");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("pbgi ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "pbgi panicked: {stderr}");
    // Ended by SIGPIPE, as `ls | head -0` ends `ls`, or without an error.
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        assert!(
            out.status.signal() == Some(13) || out.status.success(),
            "pbgi ended with {:?}: {stderr}",
            out.status
        );
    }
}
