//! Thread priorities for serving a bus on a busy machine. A served robot answers
//! within the host's reply timeout (10 ms beyond the wire time by default) or not at
//! all: on a two-core machine shared with builds (load 19-28) the reply thread of
//! `twinloop serve` waited its turn behind every runnable thread of its session (the
//! kernel shares the processor fairly between sessions first, then between their
//! threads), the simulation catching up and the CPU-bound jobs started beside it among
//! them, and the host read nothing for 5-12 s. The reply thread does a few
//! microseconds of work per request and sleeps otherwise, so it may run ahead of
//! everything. (Lowering the simulation thread's nice value instead was tried: it
//! slowed the simulation to 1.2x real time beside four busy loops where it had kept
//! 2.9x, and the host, counting the robot's seconds as the wall clock's times the
//! real-time factor, would have ramped 2.4 times faster than it thought.)

use std::io;

/// How the reply thread was favoured.
#[derive(Debug, Clone, PartialEq)]
pub enum ReplyPriority {
    /// `SCHED_FIFO` at its lowest priority: ahead of every normal thread.
    RealTime,
    /// Left at normal priority, and why (the OS refused: no `CAP_SYS_NICE`, or a
    /// zero `RLIMIT_RTPRIO`).
    Normal(String),
}

/// Run the calling thread ahead of every thread of normal priority (POSIX
/// `pthread_setschedparam` with `SCHED_FIFO`, priority 1, the lowest real-time one).
/// Threads it starts afterwards inherit this: call it on the thread that serves, after
/// starting the others. Linux's real-time throttling (`sched_rt_runtime_us`, 95 % by
/// default) keeps a thread gone wrong from taking a whole core.
pub fn favour_reply_thread() -> ReplyPriority {
    // SAFETY: a plain sched_param on the stack, for the calling thread's own handle.
    let refused = unsafe {
        let param = nix::libc::sched_param { sched_priority: 1 };
        nix::libc::pthread_setschedparam(nix::libc::pthread_self(), nix::libc::SCHED_FIFO, &param)
    };
    if refused == 0 {
        ReplyPriority::RealTime
    } else {
        ReplyPriority::Normal(io::Error::from_raw_os_error(refused).to_string())
    }
}
