//! A one-node Slurm cluster owned by a test: `munged`, `slurmctld` and `slurmd` from the Debian
//! packages (`slurm-wlm`, `munge`), started in the foreground with a configuration, a munge key
//! and state folders in a temporary folder, and killed when dropped. The node has 2 CPUs;
//! accounting storage is off (no `slurmdbd`), so failed tasks show as missing outputs, not in
//! `sacct`. Commands for the cluster come from [`Cluster::command`] (which sets `SLURM_CONF`).
//! (Included with `#[path]` by the tests that use it.)

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub struct Cluster {
    pub dir: tempfile::TempDir,
    pub conf: PathBuf,
    daemons: std::cell::RefCell<Vec<Child>>,
}

/// A free TCP port on this machine (bound and released: a race with other programs is
/// possible but unlikely).
fn free_port() -> Result<u16, String> {
    let l = TcpListener::bind("127.0.0.1:0").map_err(|e| format!("no free port: {e}"))?;
    l.local_addr()
        .map(|a| a.port())
        .map_err(|e| format!("no free port: {e}"))
}

fn found(program: &str) -> bool {
    ["/usr/sbin", "/usr/bin", "/sbin", "/bin"]
        .iter()
        .any(|d| Path::new(d).join(program).is_file())
}

impl Cluster {
    /// Starts the cluster and waits (at most 60 s) until its node is idle. `Err` says why it
    /// could not: the packages are missing, this is not root (Slurm's daemons run as root
    /// here), or a daemon did not come up.
    pub fn start() -> Result<Cluster, String> {
        for p in [
            "munged",
            "slurmctld",
            "slurmd",
            "sbatch",
            "squeue",
            "scontrol",
        ] {
            if !found(p) {
                return Err(format!(
                    "`{p}` is not installed (apt-get install slurm-wlm munge)"
                ));
            }
        }
        let uid = Command::new("id")
            .arg("-u")
            .output()
            .map_err(|e| format!("cannot run `id`: {e}"))?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("the test cluster's daemons run as root, and this is not root".into());
        }
        let dir = tempfile::Builder::new()
            .prefix("sppm-slurm")
            .tempdir()
            .map_err(|e| e.to_string())?;
        let d = dir.path().to_path_buf();
        let d = d.as_path();
        for sub in ["munge", "state", "spool", "log"] {
            std::fs::create_dir_all(d.join(sub)).map_err(|e| e.to_string())?;
        }
        use std::os::unix::fs::PermissionsExt;
        // Slurm and munge refuse folders and keys that others may write.
        for (path, mode) in [(d.to_path_buf(), 0o755), (d.join("munge"), 0o755)] {
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode))
                .map_err(|e| e.to_string())?;
        }
        let key = d.join("munge/munge.key");
        let mut random = [0u8; 1024];
        std::io::Read::read_exact(
            &mut std::fs::File::open("/dev/urandom").map_err(|e| e.to_string())?,
            &mut random,
        )
        .map_err(|e| e.to_string())?;
        std::fs::write(&key, random).map_err(|e| e.to_string())?;
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400))
            .map_err(|e| e.to_string())?;
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .map_err(|e| e.to_string())?
            .trim()
            .split('.')
            .next()
            .unwrap_or_default()
            .to_string();
        let (ctld_port, d_port) = (free_port()?, free_port()?);
        let socket = d.join("munge/munge.socket");
        let p = |s: &str| d.join(s).display().to_string();
        let conf = d.join("slurm.conf");
        let text = format!(
            "ClusterName=sppmtest\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmctldPort={ctld_port}\n\
             SlurmdPort={d_port}\n\
             AuthType=auth/munge\n\
             AuthInfo=socket={socket}\n\
             CredType=cred/munge\n\
             SlurmUser=root\n\
             SlurmdUser=root\n\
             StateSaveLocation={state}\n\
             SlurmdSpoolDir={spool}\n\
             SlurmctldPidFile={ctld_pid}\n\
             SlurmdPidFile={d_pid}\n\
             SlurmctldLogFile={ctld_log}\n\
             SlurmdLogFile={d_log}\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             JobCompType=jobcomp/none\n\
             MpiDefault=none\n\
             ReturnToService=2\n\
             SchedulerType=sched/backfill\n\
             MinJobAge=2\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN\n\
             PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            socket = socket.display(),
            state = p("state"),
            spool = p("spool"),
            ctld_pid = p("slurmctld.pid"),
            d_pid = p("slurmd.pid"),
            ctld_log = p("log/slurmctld.log"),
            d_log = p("log/slurmd.log"),
        );
        std::fs::write(&conf, text).map_err(|e| e.to_string())?;
        let cluster = Cluster {
            dir,
            conf,
            daemons: Default::default(),
        };
        let log = |name: &str| -> Result<Stdio, String> {
            std::fs::File::create(cluster.dir.path().join("log").join(name))
                .map(Stdio::from)
                .map_err(|e| e.to_string())
        };
        let mut munged = Command::new("munged");
        munged
            .args(["--foreground", "--force"])
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--log-file={}", p("munge/munged.log")))
            .arg(format!("--pid-file={}", p("munge/munged.pid")))
            .arg(format!("--seed-file={}", p("munge/munged.seed")));
        cluster.spawn(munged, log("munged.out")?)?;
        cluster.wait_for("munge's socket", Duration::from_secs(20), |c| {
            c.dir.path().join("munge/munge.socket").exists()
        })?;
        let mut ctld = cluster.command("slurmctld");
        ctld.args(["-D", "-i"]);
        cluster.spawn(ctld, log("slurmctld.out")?)?;
        let mut slurmd = cluster.command("slurmd");
        slurmd.arg("-D");
        cluster.spawn(slurmd, log("slurmd.out")?)?;
        cluster.wait_for("the node to be idle", Duration::from_secs(60), |c| {
            c.command("sinfo")
                .args(["--noheader", "--format=%t"])
                .output()
                .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        })?;
        Ok(cluster)
    }

    fn spawn(&self, mut command: Command, log: Stdio) -> Result<(), String> {
        let child = command
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("cannot start {command:?}: {e}"))?;
        self.daemons.borrow_mut().push(child);
        Ok(())
    }

    /// `program` with this cluster's configuration.
    pub fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Polls `ready` every half second until it holds; `Err` (with the daemons' logs) after
    /// `limit`, or when a daemon has exited.
    pub fn wait_for(
        &self,
        what: &str,
        limit: Duration,
        ready: impl Fn(&Cluster) -> bool,
    ) -> Result<(), String> {
        let start = Instant::now();
        loop {
            if ready(self) {
                return Ok(());
            }
            let exited = self
                .daemons
                .borrow_mut()
                .iter_mut()
                .any(|c| c.try_wait().ok().flatten().is_some());
            if exited || start.elapsed() > limit {
                return Err(format!(
                    "no {what} after {:.0} s{}:\n{}",
                    start.elapsed().as_secs_f64(),
                    if exited { " (a daemon exited)" } else { "" },
                    self.logs()
                ));
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    /// Waits until no job is queued or running, at most `limit`.
    pub fn wait_until_idle(&self, limit: Duration) -> Result<(), String> {
        self.wait_for("empty queue", limit, |c| {
            c.command("squeue")
                .args(["--noheader", "--format=%i"])
                .output()
                .is_ok_and(|o| o.status.success() && o.stdout.trim_ascii().is_empty())
        })
    }

    /// The last lines of the daemons' logs.
    pub fn logs(&self) -> String {
        let mut out = String::new();
        for name in ["munged.out", "slurmctld.out", "slurmd.out"] {
            let text =
                std::fs::read_to_string(self.dir.path().join("log").join(name)).unwrap_or_default();
            let lines: Vec<&str> = text.lines().collect();
            out += &format!(
                "--- {name}\n{}\n",
                lines[lines.len().saturating_sub(15)..].join("\n")
            );
        }
        out
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // slurmd first: it stops the jobs it runs (its children) with it.
        for child in self.daemons.get_mut().iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
