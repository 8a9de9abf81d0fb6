
using namespace System.Management.Automation
using namespace System.Management.Automation.Language

Register-ArgumentCompleter -Native -CommandName 'bearingd-lab' -ScriptBlock {
    param($wordToComplete, $commandAst, $cursorPosition)

    $commandElements = $commandAst.CommandElements
    $command = @(
        'bearingd-lab'
        for ($i = 1; $i -lt $commandElements.Count; $i++) {
            $element = $commandElements[$i]
            if ($element -isnot [StringConstantExpressionAst] -or
                $element.StringConstantType -ne [StringConstantType]::BareWord -or
                $element.Value.StartsWith('-') -or
                $element.Value -eq $wordToComplete) {
                break
        }
        $element.Value
    }) -join ';'

    $completions = @(switch ($command) {
        'bearingd-lab' {
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help')
            [CompletionResult]::new('-V', '-V ', [CompletionResultType]::ParameterName, 'Print version')
            [CompletionResult]::new('--version', '--version', [CompletionResultType]::ParameterName, 'Print version')
            [CompletionResult]::new('simulate', 'simulate', [CompletionResultType]::ParameterValue, 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV')
            [CompletionResult]::new('dataset', 'dataset', [CompletionResultType]::ParameterValue, 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log')
            [CompletionResult]::new('train', 'train', [CompletionResultType]::ParameterValue, 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`')
            [CompletionResult]::new('calibrate', 'calibrate', [CompletionResultType]::ParameterValue, 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra')
            [CompletionResult]::new('evaluate', 'evaluate', [CompletionResultType]::ParameterValue, 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon')
            [CompletionResult]::new('trend', 'trend', [CompletionResultType]::ParameterValue, 'Follow a bearing''s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot')
            [CompletionResult]::new('analyze', 'analyze', [CompletionResultType]::ParameterValue, 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)')
            [CompletionResult]::new('completions', 'completions', [CompletionResultType]::ParameterValue, 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all')
            [CompletionResult]::new('man', 'man', [CompletionResultType]::ParameterValue, 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)')
            [CompletionResult]::new('help', 'help', [CompletionResultType]::ParameterValue, 'Print this message or the help of the given subcommand(s)')
            break
        }
        'bearingd-lab;simulate' {
            [CompletionResult]::new('--model', '--model', [CompletionResultType]::ParameterName, 'Which model makes the record')
            [CompletionResult]::new('--fault', '--fault', [CompletionResultType]::ParameterName, 'The defect')
            [CompletionResult]::new('--rpm', '--rpm', [CompletionResultType]::ParameterName, 'Shaft speed, rpm')
            [CompletionResult]::new('--bearing', '--bearing', [CompletionResultType]::ParameterName, 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=9,d=7.94mm,D=39.04mm,alpha=0"')
            [CompletionResult]::new('--duration', '--duration', [CompletionResultType]::ParameterName, 'Length of the record: seconds, e.g. 10 or 10s')
            [CompletionResult]::new('--fs', '--fs', [CompletionResultType]::ParameterName, 'Sample rate, Hz')
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'Output file: .csv (one column, accel_g, in g) or .wav (32-bit float in g; an iXML chunk names its channel accel_g)')
            [CompletionResult]::new('--load', '--load', [CompletionResultType]::ParameterName, 'Physics model: radial load, N')
            [CompletionResult]::new('--defect-width', '--defect-width', [CompletionResultType]::ParameterName, 'Physics model: defect width, mm (CWRU: 0.178, 0.356, 0.533)')
            [CompletionResult]::new('--damping-ratio', '--damping-ratio', [CompletionResultType]::ParameterName, 'Physics model: damping ratio of the resonator (its resonance is --resonance)')
            [CompletionResult]::new('--dof', '--dof', [CompletionResultType]::ParameterName, 'Physics model: six degrees of freedom (seed 001) or five (seed 003)')
            [CompletionResult]::new('--calibrated', '--calibrated', [CompletionResultType]::ParameterName, 'Physics model: parameters saved by `bearingd calibrate --save` (JSON); they replace the structure (k_r, c_r, k_b, …), the defect width, the load and the model; --fault, --rpm, --fs, --duration, --noise, --jitter and --seed still apply')
            [CompletionResult]::new('--amplitude', '--amplitude', [CompletionResultType]::ParameterName, 'Signal model: impact amplitude a at full load, g')
            [CompletionResult]::new('--decay', '--decay', [CompletionResultType]::ParameterName, 'Signal model: decay rate B of each impact, 1/s')
            [CompletionResult]::new('--resonance', '--resonance', [CompletionResultType]::ParameterName, 'Structural resonance f_n, Hz (physics model: the resonator''s, which sets k_r)')
            [CompletionResult]::new('--load-zone', '--load-zone', [CompletionResultType]::ParameterName, 'Signal model: Stribeck load-zone factor ε (0.5: half the bearing loaded)')
            [CompletionResult]::new('--jitter', '--jitter', [CompletionResultType]::ParameterName, 'Impact-time jitter (slip), as a fraction of the impact period (physics model: the cage''s slip per ball pass)')
            [CompletionResult]::new('--defect-length', '--defect-length', [CompletionResultType]::ParameterName, 'Signal model: defect length in mm (0: one impact per passage; above: entry and exit impacts)')
            [CompletionResult]::new('--noise', '--noise', [CompletionResultType]::ParameterName, 'White noise, g (standard deviation)')
            [CompletionResult]::new('--machine-fault', '--machine-fault', [CompletionResultType]::ParameterName, 'Signal model: add a fault of the machine (not of the bearing) at shaft orders')
            [CompletionResult]::new('--machine-fault-velocity', '--machine-fault-velocity', [CompletionResultType]::ParameterName, 'RMS velocity of the machine fault''s 1× line, mm/s')
            [CompletionResult]::new('--onset', '--onset', [CompletionResultType]::ParameterName, 'Signal model: the fault appears at this time, s')
            [CompletionResult]::new('--seed', '--seed', [CompletionResultType]::ParameterName, 'Random seed: the same seed gives the same record')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--nuisance', '--nuisance', [CompletionResultType]::ParameterName, 'Signal model: add what a real machine adds besides the bearing (shaft harmonics, shaft-modulated noise, random impulses, a gear mesh and a 100 Hz tone; see docs/DIAGNOSIS.md)')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;dataset' {
            [CompletionResult]::new('--spec', '--spec', [CompletionResultType]::ParameterName, 'The spec (TOML): faults, records per fault, model and ranges; an example with every key: config/dataset.toml')
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'Output directory (created): dataset.npz, manifest.csv, spec.toml, and mcap/NNNNN/')
            [CompletionResult]::new('--bearing', '--bearing', [CompletionResultType]::ParameterName, 'Simulate this bearing instead of the spec''s `bearing`: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or a custom geometry. One spec makes the training set of every bearing''s model; the spec.toml written beside the set says the bearing used')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--mcap', '--mcap', [CompletionResultType]::ParameterName, 'Also write each record as a raw MCAP log (mcap/NNNNN/), replayable without a config')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;train' {
            [CompletionResult]::new('--dataset', '--dataset', [CompletionResultType]::ParameterName, 'A directory written by `bearingd dataset` (dataset.npz and spec.toml); repeat it to train on several (same classes, and same bearing on shaft orders), e.g. a signal-model and a physics set')
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'The model file to write (.safetensors)')
            [CompletionResult]::new('--epochs', '--epochs', [CompletionResultType]::ParameterName, 'Passes over the training segments')
            [CompletionResult]::new('--seed', '--seed', [CompletionResultType]::ParameterName, 'The seed of the initial weights, the corruption noise and the batch order')
            [CompletionResult]::new('--axis', '--axis', [CompletionResultType]::ParameterName, 'The input''s axis: `shaft` orders (the model knows the data set''s one bearing) or `fault-relative` orders (each fault''s own; the model serves any bearing, best trained on data sets of many, e.g. `bearing = "random"`)')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;calibrate' {
            [CompletionResult]::new('--channel', '--channel', [CompletionResultType]::ParameterName, 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)')
            [CompletionResult]::new('--column', '--column', [CompletionResultType]::ParameterName, 'Column of a CSV table: header name or 1-based index')
            [CompletionResult]::new('--fs', '--fs', [CompletionResultType]::ParameterName, 'Sample rate in Hz (overrides what the file says)')
            [CompletionResult]::new('--rpm', '--rpm', [CompletionResultType]::ParameterName, 'Shaft speed in rpm (overrides what the file says)')
            [CompletionResult]::new('--bearing', '--bearing', [CompletionResultType]::ParameterName, 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"')
            [CompletionResult]::new('--unit', '--unit', [CompletionResultType]::ParameterName, 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s')
            [CompletionResult]::new('--fault', '--fault', [CompletionResultType]::ParameterName, 'The defect to model; default: the envelope diagnosis of the record')
            [CompletionResult]::new('--band', '--band', [CompletionResultType]::ParameterName, 'The band compared, as LO-HI in Hz; default: the band the envelope analysis chose for the fault')
            [CompletionResult]::new('--load', '--load', [CompletionResultType]::ParameterName, 'Radial load on the bearing, N')
            [CompletionResult]::new('--dof', '--dof', [CompletionResultType]::ParameterName, 'The model: six degrees of freedom (seed 001) or five (seed 003)')
            [CompletionResult]::new('--population', '--population', [CompletionResultType]::ParameterName, 'Candidates per generation of the differential evolution')
            [CompletionResult]::new('--generations', '--generations', [CompletionResultType]::ParameterName, 'Generations of the differential evolution')
            [CompletionResult]::new('--simulated', '--simulated', [CompletionResultType]::ParameterName, 'Seconds simulated per candidate')
            [CompletionResult]::new('--seed', '--seed', [CompletionResultType]::ParameterName, 'Seed of the search: the same seed gives the same calibration')
            [CompletionResult]::new('--plot', '--plot', [CompletionResultType]::ParameterName, 'Draw the measured, calibrated and default spectra to this file (.png or .svg)')
            [CompletionResult]::new('--save', '--save', [CompletionResultType]::ParameterName, 'Write the calibrated parameters as JSON (for `simulate --model physics --calibrated`)')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;evaluate' {
            [CompletionResult]::new('--recordings', '--recordings', [CompletionResultType]::ParameterName, 'Instead of the simulator: every record of this manifest (CSV with a header: `file` relative to its folder, and `fault`, `note` or `life_frac` for the truth; `channel_var`, `fs_hz`, `rpm`, `bearing_geometry` where the file does not say) through `bearingd analyze` and through `bearingd import` + `replay`; writes recordings.json. May be given several times')
            [CompletionResult]::new('--false-alarm-hours', '--false-alarm-hours', [CompletionResultType]::ParameterName, 'Instead of the sweep: H hours of healthy simulated signal per machine (the full sweep''s three machines at 0.6 and 1 × nominal speed, four noise levels, with the nuisance) streamed through the daemon''s channel monitor; counts the fault flags that rise (false alarms) per hour of operation; writes false_alarms.json and false_alarms.txt. Without a value: 2 h per machine (about 2.5 min of CPU)')
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'Directory for results.json, results.csv, table.txt and pd_vs_snr.svg (with --recordings: recordings.json and recordings.txt) (created)')
            [CompletionResult]::new('--seed', '--seed', [CompletionResultType]::ParameterName, 'Seed of the sweep: the same seed gives the same records and results')
            [CompletionResult]::new('--jobs', '--jobs', [CompletionResultType]::ParameterName, 'Worker threads (default: the machine''s cores)')
            [CompletionResult]::new('--config', '--config', [CompletionResultType]::ParameterName, 'Take the analysis and threshold settings from this config file instead of the embedded default (to evaluate a tuned configuration). With `twin.learned_model` the sweep''s record path also writes agreement_grid.txt (the learned model''s agreement decided at every point of a parameter grid); with --recordings only its agreement_* keys and model are used, by both paths')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--all-channels', '--all-channels', [CompletionResultType]::ParameterName, 'With --recordings: also the other channels of each record (CWRU fan end and base, every axis of other files; IMS snapshots are always evaluated on all eight)')
            [CompletionResult]::new('--strict', '--strict', [CompletionResultType]::ParameterName, 'With --recordings: exit 1 if any answer is confident and wrong, the paths disagree on any record, or any record fails (CI)')
            [CompletionResult]::new('--quick', '--quick', [CompletionResultType]::ParameterName, 'The small sweep CI runs (both bearings at nominal speed, default severity, the simulator''s default noise and 0 dB SNR, healthy records) instead of the full one')
            [CompletionResult]::new('--no-nuisance', '--no-nuisance', [CompletionResultType]::ParameterName, 'Leave out the machine''s nuisance (shaft harmonics, modulated noise, random impulses, gear and electrical tones): bearing, 1× tone and white noise only')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;trend' {
            [CompletionResult]::new('--channel', '--channel', [CompletionResultType]::ParameterName, 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)')
            [CompletionResult]::new('--column', '--column', [CompletionResultType]::ParameterName, 'Column of a CSV table: header name or 1-based index')
            [CompletionResult]::new('--fs', '--fs', [CompletionResultType]::ParameterName, 'Sample rate in Hz (overrides what the file says)')
            [CompletionResult]::new('--rpm', '--rpm', [CompletionResultType]::ParameterName, 'Shaft speed in rpm (overrides what the file says)')
            [CompletionResult]::new('--bearing', '--bearing', [CompletionResultType]::ParameterName, 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"')
            [CompletionResult]::new('--unit', '--unit', [CompletionResultType]::ParameterName, 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--plot', '--plot', [CompletionResultType]::ParameterName, 'Draw the stage timeline (RMS with the trend, kurtosis, HW residual, fault score) to this file (.png or .svg)')
            [CompletionResult]::new('--baseline', '--baseline', [CompletionResultType]::ParameterName, 'Snapshots that form the healthy baseline (and the aging baseline of RMS)')
            [CompletionResult]::new('--smoothing', '--smoothing', [CompletionResultType]::ParameterName, 'Running median over this many snapshots before the tracker (1: none)')
            [CompletionResult]::new('--sigma', '--sigma', [CompletionResultType]::ParameterName, 'Standard deviations above a baseline that change the stage')
            [CompletionResult]::new('--trend-window', '--trend-window', [CompletionResultType]::ParameterName, 'Snapshots in the sliding window of the RMS trend')
            [CompletionResult]::new('--threshold-g', '--threshold-g', [CompletionResultType]::ParameterName, 'RMS threshold in g for the time-to-threshold (default: the failure limit the tracker learns at the start of degradation)')
            [CompletionResult]::new('--interval', '--interval', [CompletionResultType]::ParameterName, 'Seconds between snapshots whose names state no time (.mcap and .wav files; given this, any other file too, e.g. CSV tables), placed in name order')
            [CompletionResult]::new('--window', '--window', [CompletionResultType]::ParameterName, 'Records longer than 1.5 windows (IMS, MCAP logs) are cut into windows of this many seconds, each one snapshot')
            [CompletionResult]::new('--no-hw', '--no-hw', [CompletionResultType]::ParameterName, 'Do not identify the HW model per snapshot')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;analyze' {
            [CompletionResult]::new('--channel', '--channel', [CompletionResultType]::ParameterName, 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)')
            [CompletionResult]::new('--column', '--column', [CompletionResultType]::ParameterName, 'Column of a CSV table: header name or 1-based index')
            [CompletionResult]::new('--fs', '--fs', [CompletionResultType]::ParameterName, 'Sample rate in Hz (overrides what the file says)')
            [CompletionResult]::new('--rpm', '--rpm', [CompletionResultType]::ParameterName, 'Shaft speed in rpm (overrides what the file says)')
            [CompletionResult]::new('--bearing', '--bearing', [CompletionResultType]::ParameterName, 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"')
            [CompletionResult]::new('--unit', '--unit', [CompletionResultType]::ParameterName, 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--plot', '--plot', [CompletionResultType]::ParameterName, 'Draw the envelope spectrum and the kurtogram to this file (.png or .svg); with several records, the record''s file name is added before the extension. Runs in bearingd-lab')
            [CompletionResult]::new('--config', '--config', [CompletionResultType]::ParameterName, 'Take the analysis settings from this configuration file''s [analysis] section, and its twin.learned_model unless --learned is given: the daemon''s decision, offline')
            [CompletionResult]::new('--band-selection', '--band-selection', [CompletionResultType]::ParameterName, 'How to choose the resonance band')
            [CompletionResult]::new('--band', '--band', [CompletionResultType]::ParameterName, 'The band for --band-selection fixed, as LO-HI in Hz, e.g. 2000-4000')
            [CompletionResult]::new('--window', '--window', [CompletionResultType]::ParameterName, 'Envelope-spectrum window length in seconds (rounded to a power of two samples)')
            [CompletionResult]::new('--learned', '--learned', [CompletionResultType]::ParameterName, 'Add a learned model''s opinion: a .safetensors file of `bearingd train`, or a directory of them, one per bearing (the shipped ones: models/, one for each catalog bearing). It may settle what the envelope leaves open, never overrule it; the JSON gains `learned`')
            [CompletionResult]::new('--machine-group', '--machine-group', [CompletionResultType]::ParameterName, 'ISO 10816-3 machine group for the velocity zones: 1 (above 300 kW, or shaft height from 315 mm) or 2 (15 to 300 kW, shaft height 160 to 315 mm)')
            [CompletionResult]::new('--foundation', '--foundation', [CompletionResultType]::ParameterName, 'Foundation for the velocity zones: rigid or flexible')
            [CompletionResult]::new('--hw-states', '--hw-states', [CompletionResultType]::ParameterName, 'With --hw: where the median filter sits in the virtual states'' chain of differences, raw_once (the raw signal, once: the seed''s reading) or each_order (every order''s output on its own); docs/HW.md compares them')
            [CompletionResult]::new('--demo', '--demo', [CompletionResultType]::ParameterName, 'Analyse a built-in simulated record (outer-race fault, SKF 6205-2RS, 1772 rpm, 12 kHz)')
            [CompletionResult]::new('--no-refine', '--no-refine', [CompletionResultType]::ParameterName, 'Do not refine the band per fault hypothesis by its fault-band SNR')
            [CompletionResult]::new('--twin', '--twin', [CompletionResultType]::ParameterName, 'Also fit the signal-model twin for each fault hypothesis (adds `twin` to the JSON, the twin''s spectrum to the text and the plot)')
            [CompletionResult]::new('--hw', '--hw', [CompletionResultType]::ParameterName, 'Instead of the diagnosis: identify the Hammerstein–Wiener model (seed 003) for state orders 0…9 on each record and print its accuracy and time per order, and the mean per directory (bearing)')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;completions' {
            [CompletionResult]::new('--program', '--program', [CompletionResultType]::ParameterName, 'Whose command line: bearingd (the service) or bearingd-lab')
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'Write every shell''s script of both programs into this directory (docs/cli/completions is where the service''s scripts are taken from; `make cli-docs` writes it)')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'bearingd-lab;man' {
            [CompletionResult]::new('--out', '--out', [CompletionResultType]::ParameterName, 'The directory to write the pages into (created if absent): bearingd.1, bearingd-analyze.1, ..., bearingd-lab.1, bearingd-lab-train.1, ...')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help')
            break
        }
        'bearingd-lab;help' {
            [CompletionResult]::new('simulate', 'simulate', [CompletionResultType]::ParameterValue, 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV')
            [CompletionResult]::new('dataset', 'dataset', [CompletionResultType]::ParameterValue, 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log')
            [CompletionResult]::new('train', 'train', [CompletionResultType]::ParameterValue, 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`')
            [CompletionResult]::new('calibrate', 'calibrate', [CompletionResultType]::ParameterValue, 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra')
            [CompletionResult]::new('evaluate', 'evaluate', [CompletionResultType]::ParameterValue, 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon')
            [CompletionResult]::new('trend', 'trend', [CompletionResultType]::ParameterValue, 'Follow a bearing''s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot')
            [CompletionResult]::new('analyze', 'analyze', [CompletionResultType]::ParameterValue, 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)')
            [CompletionResult]::new('completions', 'completions', [CompletionResultType]::ParameterValue, 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all')
            [CompletionResult]::new('man', 'man', [CompletionResultType]::ParameterValue, 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)')
            [CompletionResult]::new('help', 'help', [CompletionResultType]::ParameterValue, 'Print this message or the help of the given subcommand(s)')
            break
        }
        'bearingd-lab;help;simulate' {
            break
        }
        'bearingd-lab;help;dataset' {
            break
        }
        'bearingd-lab;help;train' {
            break
        }
        'bearingd-lab;help;calibrate' {
            break
        }
        'bearingd-lab;help;evaluate' {
            break
        }
        'bearingd-lab;help;trend' {
            break
        }
        'bearingd-lab;help;analyze' {
            break
        }
        'bearingd-lab;help;completions' {
            break
        }
        'bearingd-lab;help;man' {
            break
        }
        'bearingd-lab;help;help' {
            break
        }
    })

    $completions.Where{ $_.CompletionText -like "$wordToComplete*" } |
        Sort-Object -Property ListItemText
}
