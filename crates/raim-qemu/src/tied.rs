//! Child processes that cannot outlive this one.
//!
//! [`QemuSession`](crate::QemuSession) kills its QEMU on drop, but a process
//! that aborts (a stack overflow, `panic = "abort"`, SIGKILL) runs no
//! destructor, and its QEMU would keep running, orphaned. On Linux the
//! child therefore asks the kernel, between `fork` and `exec`, for SIGKILL
//! when its parent dies (`prctl(PR_SET_PDEATHSIG)`, prctl(2)).
//!
//! The kernel's "parent" there is the *thread* that forked, not the process:
//! a child spawned from a test thread (or a worker-pool thread) would be
//! killed when that thread ends, while its session may still be in use on
//! another thread. So every child is forked by one spawner thread that
//! lives as long as the process, and dies only with it.

use std::io;
use std::process::{Child, Command};
use std::sync::mpsc;
use std::sync::OnceLock;

/// A spawn request: the command and where its answer goes.
type Job = (Command, mpsc::Sender<io::Result<Child>>);

/// Starts `cmd` as a child that is killed (SIGKILL) when this process ends,
/// however it ends. Elsewhere than on Linux the child is spawned as usual
/// (its owner still kills it on drop).
pub fn spawn(cmd: Command) -> io::Result<Child> {
    static SPAWNER: OnceLock<mpsc::Sender<Job>> = OnceLock::new();
    let spawner = SPAWNER.get_or_init(|| {
        let (tx, rx) = mpsc::channel::<Job>();
        // If the thread cannot start, `rx` is dropped with the closure and
        // every request below fails with the error it reports.
        let _ = std::thread::Builder::new()
            .name("raim-qemu-spawner".into())
            .spawn(move || {
                for (mut cmd, reply) in rx {
                    let _ = reply.send(spawn_here(&mut cmd));
                }
            });
        tx
    });
    let not_running = || io::Error::other("the raim-qemu spawner thread is not running");
    let (reply, answer) = mpsc::channel();
    spawner.send((cmd, reply)).map_err(|_| not_running())?;
    answer.recv().map_err(|_| not_running())?
}

/// Spawns `cmd` from the calling thread, with the parent-death signal set
/// in the child (Linux).
#[cfg(target_os = "linux")]
fn spawn_here(cmd: &mut Command) -> io::Result<Child> {
    use std::os::unix::process::CommandExt;
    let parent = std::process::id();
    // SAFETY: the hook runs in the forked child before `exec`; it calls
    // only async-signal-safe functions (prctl, getppid) and does not
    // allocate (`from_raw_os_error` and `last_os_error` build no box).
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0) != 0 {
                return Err(io::Error::last_os_error());
            }
            // The parent died between fork and prctl: no signal will come.
            if libc::getppid() as u32 != parent {
                return Err(io::Error::from_raw_os_error(libc::ESRCH));
            }
            Ok(())
        });
    }
    cmd.spawn()
}

#[cfg(not(target_os = "linux"))]
fn spawn_here(cmd: &mut Command) -> io::Result<Child> {
    cmd.spawn()
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};

    /// Set in the environment of the re-executed test binary: how its
    /// parent-role test spawns its child ("tied" or "plain").
    const ROLE_ENV: &str = "RAIM_QEMU_TIED_TEST_ROLE";
    /// How long the killed parent's child may take to die: the signal is
    /// delivered at once; this bounds a loaded machine's scheduling.
    const DEATH_TIMEOUT: Duration = Duration::from_secs(10);
    /// How long the control (a plainly spawned child) must survive its
    /// parent: far beyond the milliseconds a tied child takes to die.
    const SURVIVAL: Duration = Duration::from_secs(1);

    /// Whether process `pid` runs (exists and is not a zombie).
    fn running(pid: u32) -> bool {
        match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
            // Field 3, after the parenthesised command name, is the state.
            Ok(stat) => stat
                .rsplit_once(')')
                .and_then(|(_, rest)| rest.split_whitespace().next())
                .is_some_and(|state| state != "Z" && state != "X"),
            Err(_) => false,
        }
    }

    /// The parent's role, run in a re-executed copy of this test binary
    /// (ignored otherwise): spawns `sleep 120` as its role says, prints
    /// the child's pid and waits to be killed.
    #[test]
    #[ignore = "run only as the parent of parent_death_kills_a_tied_child"]
    fn parent_role() {
        let Ok(role) = std::env::var(ROLE_ENV) else {
            return;
        };
        let mut cmd = Command::new("sleep");
        cmd.arg("120").stdout(Stdio::null());
        let child = if role == "tied" {
            super::spawn(cmd).unwrap()
        } else {
            cmd.spawn().unwrap()
        };
        println!("CHILD_PID={}", child.id());
        std::thread::sleep(Duration::from_secs(120));
    }

    /// Runs `parent_role` in a new process, kills that process (SIGKILL:
    /// no destructor runs) and returns its child's pid and whether the
    /// child was gone within `wait`.
    fn kill_parent(role: &str, wait: Duration) -> (u32, bool) {
        let mut parent = Command::new(std::env::current_exe().unwrap())
            .args(["tied::tests::parent_role", "--exact", "--ignored"])
            .args(["--nocapture", "--test-threads=1"])
            .env(ROLE_ENV, role)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let stdout = parent.stdout.take().unwrap();
        let pid: u32 = BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
            // The harness prints "test ... " before the test's own output.
            .find_map(|l| l.split_once("CHILD_PID=").map(|(_, pid)| pid.to_owned()))
            .expect("the parent role printed its child's pid")
            .parse()
            .unwrap();
        assert!(running(pid), "{role}: the child runs before the kill");
        parent.kill().unwrap();
        parent.wait().unwrap();
        let start = Instant::now();
        while running(pid) && start.elapsed() < wait {
            std::thread::sleep(Duration::from_millis(20));
        }
        (pid, !running(pid))
    }

    /// A child spawned through `spawn` dies with its parent process; a
    /// plainly spawned one (the control, killed here afterwards) survives
    /// it, which shows the check can fail.
    #[test]
    fn parent_death_kills_a_tied_child() {
        let (_, tied_gone) = kill_parent("tied", DEATH_TIMEOUT);
        assert!(tied_gone, "a tied child outlived its parent");
        let (pid, plain_gone) = kill_parent("plain", SURVIVAL);
        // SAFETY: kill(2) on a pid this test observed; no memory involved.
        unsafe { libc::kill(pid as libc::pid_t, libc::SIGKILL) };
        assert!(!plain_gone, "the control child died with its parent");
    }
}
