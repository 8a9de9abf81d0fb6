# Print an optspec for argparse to handle cmd's options that are independent of any subcommand.
function __fish_bearingd_lab_global_optspecs
    string join \n h/help V/version
end

function __fish_bearingd_lab_needs_command
    # Figure out if the current invocation already has a command.
    set -l cmd (commandline -opc)
    set -e cmd[1]
    argparse -s (__fish_bearingd_lab_global_optspecs) -- $cmd 2>/dev/null
    or return
    if set -q argv[1]
        # Also print the command, so this can be used to figure out what it is.
        echo $argv[1]
        return 1
    end
    return 0
end

function __fish_bearingd_lab_using_subcommand
    set -l cmd (__fish_bearingd_lab_needs_command)
    test -z "$cmd"
    and return 1
    contains -- $cmd[1] $argv
end

complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -s h -l help -d 'Print help'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -s V -l version -d 'Print version'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "simulate" -d 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "dataset" -d 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "train" -d 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "calibrate" -d 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "evaluate" -d 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "trend" -d 'Follow a bearing\'s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "analyze" -d 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "completions" -d 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "man" -d 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)'
complete -c bearingd-lab -n "__fish_bearingd_lab_needs_command" -f -a "help" -d 'Print this message or the help of the given subcommand(s)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l model -d 'Which model makes the record' -r -f -a "signal\t'The signal model: decaying impacts on a resonance (fast, every shape parameter free)'
physics\t'The physics twin: masses, springs and Hertz contacts integrated in time'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l fault -d 'The defect' -r -f -a "none\t''
outer\t''
inner\t''
ball\t''
cage\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l rpm -d 'Shaft speed, rpm' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l bearing -d 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=9,d=7.94mm,D=39.04mm,alpha=0"' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l duration -d 'Length of the record: seconds, e.g. 10 or 10s' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l fs -d 'Sample rate, Hz' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l out -d 'Output file: .csv (one column, accel_g, in g) or .wav (32-bit float in g; an iXML chunk names its channel accel_g)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l load -d 'Physics model: radial load, N' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l defect-width -d 'Physics model: defect width, mm (CWRU: 0.178, 0.356, 0.533)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l damping-ratio -d 'Physics model: damping ratio of the resonator (its resonance is --resonance)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l dof -d 'Physics model: six degrees of freedom (seed 001) or five (seed 003)' -r -f -a "six\t'Seed 001: shaft, housing and a resonator, each in x and y'
five\t'Seed 003: the resonator in y only'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l calibrated -d 'Physics model: parameters saved by `bearingd calibrate --save` (JSON); they replace the structure (k_r, c_r, k_b, …), the defect width, the load and the model; --fault, --rpm, --fs, --duration, --noise, --jitter and --seed still apply' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l amplitude -d 'Signal model: impact amplitude a at full load, g' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l decay -d 'Signal model: decay rate B of each impact, 1/s' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l resonance -d 'Structural resonance f_n, Hz (physics model: the resonator\'s, which sets k_r)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l load-zone -d 'Signal model: Stribeck load-zone factor ε (0.5: half the bearing loaded)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l jitter -d 'Impact-time jitter (slip), as a fraction of the impact period (physics model: the cage\'s slip per ball pass)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l defect-length -d 'Signal model: defect length in mm (0: one impact per passage; above: entry and exit impacts)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l noise -d 'White noise, g (standard deviation)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l machine-fault -d 'Signal model: add a fault of the machine (not of the bearing) at shaft orders' -r -f -a "unbalance\t'A 1× line (once per revolution)'
misalignment\t'2× stronger than 1×, some 3×'
looseness\t'Many running-speed harmonics and half orders'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l machine-fault-velocity -d 'RMS velocity of the machine fault\'s 1× line, mm/s' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l onset -d 'Signal model: the fault appears at this time, s' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l seed -d 'Random seed: the same seed gives the same record' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document, or one object per line for a stream of events; notes and warnings are in the object'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -l nuisance -d 'Signal model: add what a real machine adds besides the bearing (shaft harmonics, shaft-modulated noise, random impulses, a gear mesh and a 100 Hz tone; see docs/DIAGNOSIS.md)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand simulate" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -l spec -d 'The spec (TOML): faults, records per fault, model and ranges; an example with every key: config/dataset.toml' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -l out -d 'Output directory (created): dataset.npz, manifest.csv, spec.toml, and mcap/NNNNN/' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -l bearing -d 'Simulate this bearing instead of the spec\'s `bearing`: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or a custom geometry. One spec makes the training set of every bearing\'s model; the spec.toml written beside the set says the bearing used' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document, or one object per line for a stream of events; notes and warnings are in the object'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -l mcap -d 'Also write each record as a raw MCAP log (mcap/NNNNN/), replayable without a config'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand dataset" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l dataset -d 'A directory written by `bearingd dataset` (dataset.npz and spec.toml); repeat it to train on several (same classes, and same bearing on shaft orders), e.g. a signal-model and a physics set' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l out -d 'The model file to write (.safetensors)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l epochs -d 'Passes over the training segments' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l seed -d 'The seed of the initial weights, the corruption noise and the batch order' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l axis -d 'The input\'s axis: `shaft` orders (the model knows the data set\'s one bearing) or `fault-relative` orders (each fault\'s own; the model serves any bearing, best trained on data sets of many, e.g. `bearing = "random"`)' -r -f -a "shaft\t''
fault-relative\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document, or one object per line for a stream of events; notes and warnings are in the object'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand train" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l channel -d 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l column -d 'Column of a CSV table: header name or 1-based index' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l fs -d 'Sample rate in Hz (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l rpm -d 'Shaft speed in rpm (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l bearing -d 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l unit -d 'Unit of the file\'s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s' -r -f -a "g\t'Acceleration in g'
m/s2\t'Acceleration in m/s²'
full-scale\t'Relative amplitudes (fractions of a recorder\'s full scale)'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l fault -d 'The defect to model; default: the envelope diagnosis of the record' -r -f -a "none\t''
outer\t''
inner\t''
ball\t''
cage\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l band -d 'The band compared, as LO-HI in Hz; default: the band the envelope analysis chose for the fault' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l load -d 'Radial load on the bearing, N' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l dof -d 'The model: six degrees of freedom (seed 001) or five (seed 003)' -r -f -a "six\t'Seed 001: shaft, housing and a resonator, each in x and y'
five\t'Seed 003: the resonator in y only'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l population -d 'Candidates per generation of the differential evolution' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l generations -d 'Generations of the differential evolution' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l simulated -d 'Seconds simulated per candidate' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l seed -d 'Seed of the search: the same seed gives the same calibration' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l plot -d 'Draw the measured, calibrated and default spectra to this file (.png or .svg)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l save -d 'Write the calibrated parameters as JSON (for `simulate --model physics --calibrated`)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document, or one object per line for a stream of events; notes and warnings are in the object'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand calibrate" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l recordings -d 'Instead of the simulator: every record of this manifest (CSV with a header: `file` relative to its folder, and `fault`, `note` or `life_frac` for the truth; `channel_var`, `fs_hz`, `rpm`, `bearing_geometry` where the file does not say) through `bearingd analyze` and through `bearingd import` + `replay`; writes recordings.json. May be given several times' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l false-alarm-hours -d 'Instead of the sweep: H hours of healthy simulated signal per machine (the full sweep\'s three machines at 0.6 and 1 × nominal speed, four noise levels, with the nuisance) streamed through the daemon\'s channel monitor; counts the fault flags that rise (false alarms) per hour of operation; writes false_alarms.json and false_alarms.txt. Without a value: 2 h per machine (about 2.5 min of CPU)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l out -d 'Directory for results.json, results.csv, table.txt and pd_vs_snr.svg (with --recordings: recordings.json and recordings.txt) (created)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l seed -d 'Seed of the sweep: the same seed gives the same records and results' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l jobs -d 'Worker threads (default: the machine\'s cores)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l config -d 'Take the analysis and threshold settings from this config file instead of the embedded default (to evaluate a tuned configuration). With `twin.learned_model` the sweep\'s record path also writes agreement_grid.txt (the learned model\'s agreement decided at every point of a parameter grid); with --recordings only its agreement_* keys and model are used, by both paths' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document, or one object per line for a stream of events; notes and warnings are in the object'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l all-channels -d 'With --recordings: also the other channels of each record (CWRU fan end and base, every axis of other files; IMS snapshots are always evaluated on all eight)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l strict -d 'With --recordings: exit 1 if any answer is confident and wrong, the paths disagree on any record, or any record fails (CI)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l quick -d 'The small sweep CI runs (both bearings at nominal speed, default severity, the simulator\'s default noise and 0 dB SNR, healthy records) instead of the full one'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -l no-nuisance -d 'Leave out the machine\'s nuisance (shaft harmonics, modulated noise, random impulses, gear and electrical tones): bearing, 1× tone and white noise only'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand evaluate" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l channel -d 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l column -d 'Column of a CSV table: header name or 1-based index' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l fs -d 'Sample rate in Hz (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l rpm -d 'Shaft speed in rpm (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l bearing -d 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l unit -d 'Unit of the file\'s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s' -r -f -a "g\t'Acceleration in g'
m/s2\t'Acceleration in m/s²'
full-scale\t'Relative amplitudes (fractions of a recorder\'s full scale)'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document (`analyze` of several records: an array of them)'
table\t'One Markdown table row per record (per snapshot for `trend`)'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l plot -d 'Draw the stage timeline (RMS with the trend, kurtosis, HW residual, fault score) to this file (.png or .svg)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l baseline -d 'Snapshots that form the healthy baseline (and the aging baseline of RMS)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l smoothing -d 'Running median over this many snapshots before the tracker (1: none)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l sigma -d 'Standard deviations above a baseline that change the stage' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l trend-window -d 'Snapshots in the sliding window of the RMS trend' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l threshold-g -d 'RMS threshold in g for the time-to-threshold (default: the failure limit the tracker learns at the start of degradation)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l interval -d 'Seconds between snapshots whose names state no time (.mcap and .wav files; given this, any other file too, e.g. CSV tables), placed in name order' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l window -d 'Records longer than 1.5 windows (IMS, MCAP logs) are cut into windows of this many seconds, each one snapshot' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -l no-hw -d 'Do not identify the HW model per snapshot'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand trend" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l channel -d 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l column -d 'Column of a CSV table: header name or 1-based index' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l fs -d 'Sample rate in Hz (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l rpm -d 'Shaft speed in rpm (overrides what the file says)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l bearing -d 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l unit -d 'Unit of the file\'s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s' -r -f -a "g\t'Acceleration in g'
m/s2\t'Acceleration in m/s²'
full-scale\t'Relative amplitudes (fractions of a recorder\'s full scale)'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l format -d 'Output format' -r -f -a "text\t'Lines for people'
json\t'JSON on stdout: one document (`analyze` of several records: an array of them)'
table\t'One Markdown table row per record (per snapshot for `trend`)'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l plot -d 'Draw the envelope spectrum and the kurtogram to this file (.png or .svg); with several records, the record\'s file name is added before the extension. Runs in bearingd-lab' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l config -d 'Take the analysis settings from this configuration file\'s [analysis] section, and its twin.learned_model unless --learned is given: the daemon\'s decision, offline' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l band-selection -d 'How to choose the resonance band' -r -f -a "kurtogram\t''
gk\t''
fixed\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l band -d 'The band for --band-selection fixed, as LO-HI in Hz, e.g. 2000-4000' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l window -d 'Envelope-spectrum window length in seconds (rounded to a power of two samples)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l learned -d 'Add a learned model\'s opinion: a .safetensors file of `bearingd train`, or a directory of them, one per bearing (the shipped ones: models/, one for each catalog bearing). It may settle what the envelope leaves open, never overrule it; the JSON gains `learned`' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l machine-group -d 'ISO 10816-3 machine group for the velocity zones: 1 (above 300 kW, or shaft height from 315 mm) or 2 (15 to 300 kW, shaft height 160 to 315 mm)' -r
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l foundation -d 'Foundation for the velocity zones: rigid or flexible' -r -f -a "rigid\t''
flexible\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l hw-states -d 'With --hw: where the median filter sits in the virtual states\' chain of differences, raw_once (the raw signal, once: the seed\'s reading) or each_order (every order\'s output on its own); docs/HW.md compares them' -r -f -a "raw-once\t''
each-order\t''"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l demo -d 'Analyse a built-in simulated record (outer-race fault, SKF 6205-2RS, 1772 rpm, 12 kHz)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l no-refine -d 'Do not refine the band per fault hypothesis by its fault-band SNR'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l twin -d 'Also fit the signal-model twin for each fault hypothesis (adds `twin` to the JSON, the twin\'s spectrum to the text and the plot)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -l hw -d 'Instead of the diagnosis: identify the Hammerstein–Wiener model (seed 003) for state orders 0…9 on each record and print its accuracy and time per order, and the mean per directory (bearing)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand analyze" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand completions" -l program -d 'Whose command line: bearingd (the service) or bearingd-lab' -r -f -a "bearingd\t'The service, `bearingd`'
bearingd-lab\t'The lab, `bearingd-lab`'"
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand completions" -l out -d 'Write every shell\'s script of both programs into this directory (docs/cli/completions is where the service\'s scripts are taken from; `make cli-docs` writes it)' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand completions" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand man" -l out -d 'The directory to write the pages into (created if absent): bearingd.1, bearingd-analyze.1, ..., bearingd-lab.1, bearingd-lab-train.1, ...' -r -F
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand man" -s h -l help -d 'Print help'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "simulate" -d 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "dataset" -d 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "train" -d 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "calibrate" -d 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "evaluate" -d 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "trend" -d 'Follow a bearing\'s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "analyze" -d 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "completions" -d 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "man" -d 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)'
complete -c bearingd-lab -n "__fish_bearingd_lab_using_subcommand help; and not __fish_seen_subcommand_from simulate dataset train calibrate evaluate trend analyze completions man help" -f -a "help" -d 'Print this message or the help of the given subcommand(s)'
