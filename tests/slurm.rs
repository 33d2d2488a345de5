//! The README's Slurm recipes (`tools/slurm/part.sh`, `tools/slurm/record.sh`, shown verbatim in
//! README.md) submitted with `sbatch --array` to a real single-node Slurm that the test starts
//! in a temporary folder: a still rendered in parts and merged must be byte for byte the image
//! of one render, and a recording in frame chunks must be byte for byte the frames of one run.
//!
//! The cluster: `munged` with its own key and socket, `slurmctld` and `slurmd` (Debian's `munge`
//! and `slurm-wlm`) in the foreground, on free local ports, with a generated `slurm.conf`: its
//! own state, spool and log files, the current user as `SlurmUser`, no cgroups
//! (`proctrack/linuxproc`, `task/none`), one node with what `slurmd -C` finds on this machine.
//! A guard cancels the jobs and stops the daemons when the test ends, failed or not. Where the
//! programs are missing or the daemons do not come up, the test skips with a loud message,
//! unless `CI` or `NLIFS_REQUIRE_TOOLS=1` is set (`.ci/run` installs the packages): there it
//! fails with the daemons' logs.

mod common;

use std::net::TcpListener;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// How long the daemons get to come up, and the jobs to finish (each takes seconds here).
const START_TIMEOUT: Duration = Duration::from_secs(40);
const JOB_TIMEOUT: Duration = Duration::from_secs(180);

/// The programs the cluster needs.
const PROGRAMS: [&str; 7] = ["munged", "slurmctld", "slurmd", "sbatch", "sinfo", "scancel", "squeue"];

/// A single-node Slurm in `dir`; dropping it cancels its jobs and stops its daemons.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    /// munged, slurmctld, slurmd: stopped in reverse order.
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    /// Starts munged, slurmctld and slurmd and waits until the node is idle. Err says what did
    /// not work, with the logs.
    fn start(dir: &Path) -> Result<Cluster, String> {
        if let Some(missing) = PROGRAMS.iter().find(|p| !on_path(p)) {
            return Err(format!("`{missing}` is not installed (Debian: slurm-wlm munge)"));
        }
        // munged wants every folder above its socket searchable by all.
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).map_err(|e| e.to_string())?;
        for sub in ["state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub)).map_err(|e| e.to_string())?;
        }
        let mut cluster = Cluster { dir: dir.to_path_buf(), conf: dir.join("slurm.conf"), daemons: Vec::new() };

        let key = dir.join("munge.key");
        let mut bytes = vec![0u8; 1024];
        std::io::Read::read_exact(&mut std::fs::File::open("/dev/urandom").map_err(|e| e.to_string())?, &mut bytes)
            .map_err(|e| e.to_string())?;
        std::fs::write(&key, &bytes).map_err(|e| e.to_string())?;
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o600)).map_err(|e| e.to_string())?;
        let socket = dir.join("munge.socket");
        let mut munged = Command::new("munged");
        munged.arg("--foreground").arg("--key-file").arg(&key).arg("--socket").arg(&socket);
        for (flag, file) in [("--log-file", "munged.log"), ("--pid-file", "munged.pid"), ("--seed-file", "munged.seed")]
        {
            munged.arg(flag).arg(dir.join(file));
        }
        cluster.spawn("munged", munged)?;
        cluster.wait_until("munged's socket", || socket.exists())?;

        let node = node_line()?;
        let user = output_of(Command::new("id").arg("-un"))?;
        let [ctld_port, slurmd_port] = [free_port()?, free_port()?];
        let plugstack = dir.join("plugstack.conf");
        std::fs::write(&plugstack, "").map_err(|e| e.to_string())?;
        let d = dir.display();
        let conf = format!(
            "ClusterName=nlifs-test\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmUser={user}\nSlurmdUser={user}\n\
             SlurmctldPort={ctld_port}\nSlurmdPort={slurmd_port}\n\
             AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket={socket}\n\
             StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
             PlugStackConfig={plugstack}\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n\
             JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
             JobCompType=jobcomp/none\nMpiDefault=none\nReturnToService=2\n\
             NodeName={host} NodeAddr=127.0.0.1 {resources} State=UNKNOWN\n\
             PartitionName=test Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            host = node.0,
            resources = node.1,
            socket = socket.display(),
            plugstack = plugstack.display(),
        );
        std::fs::write(&cluster.conf, conf).map_err(|e| e.to_string())?;

        let mut ctld = Command::new("slurmctld");
        ctld.arg("-D").arg("-f").arg(&cluster.conf);
        cluster.spawn("slurmctld", ctld)?;
        let mut slurmd = Command::new("slurmd");
        slurmd.arg("-D").arg("-f").arg(&cluster.conf);
        cluster.spawn("slurmd", slurmd)?;
        let conf = cluster.conf.clone();
        cluster.wait_until("the node to be idle", || {
            Command::new("sinfo")
                .args(["-h", "-o", "%T"])
                .env("SLURM_CONF", &conf)
                .output()
                .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        })?;
        Ok(cluster)
    }

    /// Starts a daemon with its output in `log/NAME.out`.
    fn spawn(&mut self, name: &'static str, mut command: Command) -> Result<(), String> {
        let out = std::fs::File::create(self.dir.join("log").join(format!("{name}.out"))).map_err(|e| e.to_string())?;
        let err = out.try_clone().map_err(|e| e.to_string())?;
        let child = command
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .spawn()
            .map_err(|e| format!("{name} does not start: {e}"))?;
        self.daemons.push((name, child));
        Ok(())
    }

    /// Polls `ready` until it holds; Err with the logs when a daemon exits or time runs out.
    fn wait_until(&mut self, what: &str, mut ready: impl FnMut() -> bool) -> Result<(), String> {
        let start = Instant::now();
        while !ready() {
            let exited = self.daemons.iter_mut().find_map(|(name, child)| Some((*name, child.try_wait().ok()??)));
            if let Some((name, status)) = exited {
                return Err(format!("{name} exited ({status}) while waiting for {what}\n{}", self.logs()));
            }
            if start.elapsed() > START_TIMEOUT {
                return Err(format!("no {what} after {START_TIMEOUT:?}\n{}", self.logs()));
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        Ok(())
    }

    /// The last lines of every log of the cluster.
    fn logs(&self) -> String {
        let mut text = String::new();
        let mut files: Vec<PathBuf> =
            std::fs::read_dir(self.dir.join("log")).into_iter().flatten().flatten().map(|e| e.path()).collect();
        files.sort();
        for file in files {
            let body = std::fs::read_to_string(&file).unwrap_or_default();
            let lines: Vec<&str> = body.lines().collect();
            let tail = lines[lines.len().saturating_sub(25)..].join("\n");
            text += &format!("--- {} (last lines)\n{tail}\n", file.display());
        }
        text
    }

    /// A command of the cluster's client tools, run in the repository (as the README's are).
    fn client(&self, program: &str) -> Command {
        let mut command = Command::new(program);
        command.env("SLURM_CONF", &self.conf).current_dir(env!("CARGO_MANIFEST_DIR"));
        command
    }

    /// `sbatch --wait --array=ARRAY SCRIPT ARGS` with this test's nlifs first on the PATH, one CPU
    /// a task (the scripts ask for 8; the command line overrides `#SBATCH`); panics with the
    /// tasks' output unless every task succeeds within [`JOB_TIMEOUT`].
    fn run_array(&self, name: &str, array: &str, script: &str, args: &[String]) {
        let bin = Path::new(env!("CARGO_BIN_EXE_nlifs")).parent().unwrap();
        let path = std::env::join_paths(
            std::iter::once(bin.to_path_buf())
                .chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
        )
        .unwrap();
        let output = self.dir.join(format!("{name}-%a.out"));
        let mut sbatch = self.client("sbatch");
        sbatch
            .args(["--wait", "--cpus-per-task=1", "--time=5", "--job-name", name])
            .arg(format!("--array={array}"))
            .arg(format!("--output={}", output.display()))
            .arg(script)
            .args(args)
            .env("PATH", path)
            .env("NLIFS_CONFIG_DIR", self.dir.join("nlifs-config"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = sbatch.spawn().unwrap_or_else(|e| panic!("sbatch does not start: {e}"));
        let start = Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if start.elapsed() > JOB_TIMEOUT {
                let _ = child.kill();
                let _ = child.wait();
                panic!("{name}: the job array did not finish in {JOB_TIMEOUT:?}\n{}", self.job_outputs(name));
            }
            std::thread::sleep(Duration::from_millis(200));
        };
        let out = child.wait_with_output().unwrap();
        assert!(
            status.success(),
            "{name}: sbatch --wait {status}: {}{}\n{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
            self.job_outputs(name),
            self.logs()
        );
    }

    /// The outputs of the tasks of job `name`.
    fn job_outputs(&self, name: &str) -> String {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&self.dir)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.file_name().is_some_and(|f| f.to_string_lossy().starts_with(&format!("{name}-"))))
            .collect();
        files.sort();
        files
            .iter()
            .map(|f| format!("--- {}\n{}", f.display(), std::fs::read_to_string(f).unwrap_or_default()))
            .collect()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if self.daemons.len() == 3 {
            // Cancel what is left, so that no job step outlives slurmd.
            let _ = self.client("scancel").arg("--user").arg(whoami()).status();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                let queue = self.client("squeue").args(["-h", "-o", "%i"]).output();
                if queue.is_ok_and(|q| q.status.success() && q.stdout.is_empty()) {
                    break;
                }
                std::thread::sleep(Duration::from_millis(200));
            }
        }
        while let Some((_, mut child)) = self.daemons.pop() {
            // SIGTERM first (the daemons shut down cleanly), SIGKILL after 10 s.
            let _ = Command::new("kill").arg("-TERM").arg(child.id().to_string()).status();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) && matches!(child.try_wait(), Ok(None)) {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn whoami() -> String {
    output_of(Command::new("id").arg("-un")).unwrap_or_default()
}

/// Whether `program` is on the PATH.
fn on_path(program: &str) -> bool {
    std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
        .chain([PathBuf::from("/usr/sbin"), PathBuf::from("/sbin")])
        .any(|dir| dir.join(program).is_file())
}

/// The trimmed stdout of a command that must succeed.
fn output_of(command: &mut Command) -> Result<String, String> {
    let out: Output = command.output().map_err(|e| format!("{command:?}: {e}"))?;
    if !out.status.success() {
        return Err(format!("{command:?}: {}", String::from_utf8_lossy(&out.stderr)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// (host name, `CPUs=… RealMemory=…`): this machine as `slurmd -C` describes it.
fn node_line() -> Result<(String, String), String> {
    let text = output_of(Command::new("slurmd").arg("-C"))?;
    let line = text.lines().next().unwrap_or_default();
    let mut host = None;
    let mut resources = Vec::new();
    for field in line.split_whitespace() {
        match field.split_once('=') {
            Some(("NodeName", name)) => host = Some(name.to_string()),
            Some(_) => resources.push(field),
            None => {}
        }
    }
    let host = host.ok_or_else(|| format!("no NodeName in `slurmd -C`: {text}"))?;
    Ok((host, resources.join(" ")))
}

/// A TCP port free on this machine right now.
fn free_port() -> Result<u16, String> {
    let listener = TcpListener::bind("127.0.0.1:0").map_err(|e| e.to_string())?;
    listener.local_addr().map(|a| a.port()).map_err(|e| e.to_string())
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The files of `dir` (sorted by name).
fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
}

/// Runs nlifs; panics with its stderr unless it succeeds.
fn nlifs(args: &[&str]) -> String {
    let out = common::run_nlifs(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "nlifs {}: {stderr}", args.join(" "));
    stderr
}

#[test]
fn readme_shows_the_slurm_recipes_verbatim() {
    let readme = std::fs::read_to_string(common::repo_path("README.md")).unwrap();
    for script in ["tools/slurm/part.sh", "tools/slurm/record.sh"] {
        let body = std::fs::read_to_string(common::repo_path(script)).unwrap();
        assert!(readme.contains(&format!("```sh\n{body}```\n")), "README.md does not show {script} as it is");
        assert!(readme.contains(&format!("]({script})")), "README.md does not link {script}");
    }
}

#[test]
fn job_arrays_give_the_bytes_of_one_run() {
    let dir = common::temp_dir("slurm");
    let cluster = match Cluster::start(&dir) {
        Ok(cluster) => cluster,
        Err(why) => {
            let why = format!("no single-node Slurm here: {why}");
            assert!(!common::tools_required(), "CI or NLIFS_REQUIRE_TOOLS=1 but {why}");
            eprintln!("\n*** SKIPPED: {why} ***\n");
            return;
        }
    };

    // A still in 3 parts (one per task; 5 chunks of 64 × 4096 points), merged.
    let parts = dir.join("parts");
    let still: Vec<String> =
        ["scenes/plant2.toml", s(&parts), "--width", "80", "--height", "60", "--points", "1100000", "--seed", "3"]
            .map(String::from)
            .to_vec();
    cluster.run_array("part", "1-3", "tools/slurm/part.sh", &still);
    let part_files = files_in(&parts);
    assert_eq!(part_files.len(), 3, "one part per task: {part_files:?}");
    let (merged, one) = (dir.join("merged.png"), dir.join("one.png"));
    let mut merge = vec!["merge"];
    merge.extend(part_files.iter().map(|p| s(p)));
    merge.extend(["-o", s(&merged)]);
    nlifs(&merge);
    let scene = common::scene_path("plant2");
    let options: Vec<&str> = still[2..].iter().map(String::as_str).collect();
    nlifs(&[&["render", s(&scene)], &options[..], &["-o", s(&one)]].concat());
    assert!(
        std::fs::read(&merged).unwrap() == std::fs::read(&one).unwrap(),
        "the merged still differs from one render"
    );

    // twist-anim's 4 s at 2 fps: 8 frames in chunks of 3, 3 and 2.
    let frames = dir.join("frames");
    let options =
        ["--fps", "2", "--width", "64", "--height", "48", "--points-per-frame", "20000"].map(String::from).to_vec();
    let recipe = [vec!["scenes/twist-anim.toml".to_string(), s(&frames).to_string()], options.clone()].concat();
    cluster.run_array("record", "0-2", "tools/slurm/record.sh", &recipe);
    let scene = common::scene_path("twist-anim");
    let options: Vec<&str> = options.iter().map(String::as_str).collect();
    let stderr = nlifs(&[&["record", s(&scene), "-o", s(&frames)], &options[..], &["--resume"]].concat());
    assert!(stderr.contains("8 of 8 frames already complete"), "the array left frames to do: {stderr}");
    let whole = dir.join("whole");
    nlifs(&[&["record", s(&scene), "-o", s(&whole)], &options[..], &["--backend", "cpu"]].concat());
    let (chunked, single) = (files_in(&frames), files_in(&whole));
    let names = |files: &[PathBuf]| files.iter().map(|f| f.file_name().unwrap().to_owned()).collect::<Vec<_>>();
    assert_eq!(names(&chunked), names(&single), "the same frame files");
    assert_eq!(chunked.len(), 8);
    for (a, b) in chunked.iter().zip(&single) {
        assert!(std::fs::read(a).unwrap() == std::fs::read(b).unwrap(), "{} differs from one run's frame", a.display());
    }
    drop(cluster);
}
