
use builtin;
use str;

set edit:completion:arg-completer[bearingd-lab] = {|@words|
    fn spaces {|n|
        builtin:repeat $n ' ' | str:join ''
    }
    fn cand {|text desc|
        edit:complex-candidate $text &display=$text' '(spaces (- 14 (wcswidth $text)))$desc
    }
    var command = 'bearingd-lab'
    for word $words[1..-1] {
        if (str:has-prefix $word '-') {
            break
        }
        set command = $command';'$word
    }
    var completions = [
        &'bearingd-lab'= {
            cand -h 'Print help'
            cand --help 'Print help'
            cand -V 'Print version'
            cand --version 'Print version'
            cand simulate 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV'
            cand dataset 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log'
            cand train 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`'
            cand calibrate 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra'
            cand evaluate 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon'
            cand trend 'Follow a bearing''s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot'
            cand analyze 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)'
            cand completions 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all'
            cand man 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)'
            cand help 'Print this message or the help of the given subcommand(s)'
        }
        &'bearingd-lab;simulate'= {
            cand --model 'Which model makes the record'
            cand --fault 'The defect'
            cand --rpm 'Shaft speed, rpm'
            cand --bearing 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=9,d=7.94mm,D=39.04mm,alpha=0"'
            cand --duration 'Length of the record: seconds, e.g. 10 or 10s'
            cand --fs 'Sample rate, Hz'
            cand --out 'Output file: .csv (one column, accel_g, in g) or .wav (32-bit float in g; an iXML chunk names its channel accel_g)'
            cand --load 'Physics model: radial load, N'
            cand --defect-width 'Physics model: defect width, mm (CWRU: 0.178, 0.356, 0.533)'
            cand --damping-ratio 'Physics model: damping ratio of the resonator (its resonance is --resonance)'
            cand --dof 'Physics model: six degrees of freedom (seed 001) or five (seed 003)'
            cand --calibrated 'Physics model: parameters saved by `bearingd calibrate --save` (JSON); they replace the structure (k_r, c_r, k_b, …), the defect width, the load and the model; --fault, --rpm, --fs, --duration, --noise, --jitter and --seed still apply'
            cand --amplitude 'Signal model: impact amplitude a at full load, g'
            cand --decay 'Signal model: decay rate B of each impact, 1/s'
            cand --resonance 'Structural resonance f_n, Hz (physics model: the resonator''s, which sets k_r)'
            cand --load-zone 'Signal model: Stribeck load-zone factor ε (0.5: half the bearing loaded)'
            cand --jitter 'Impact-time jitter (slip), as a fraction of the impact period (physics model: the cage''s slip per ball pass)'
            cand --defect-length 'Signal model: defect length in mm (0: one impact per passage; above: entry and exit impacts)'
            cand --noise 'White noise, g (standard deviation)'
            cand --machine-fault 'Signal model: add a fault of the machine (not of the bearing) at shaft orders'
            cand --machine-fault-velocity 'RMS velocity of the machine fault''s 1× line, mm/s'
            cand --onset 'Signal model: the fault appears at this time, s'
            cand --seed 'Random seed: the same seed gives the same record'
            cand --format 'Output format'
            cand --nuisance 'Signal model: add what a real machine adds besides the bearing (shaft harmonics, shaft-modulated noise, random impulses, a gear mesh and a 100 Hz tone; see docs/DIAGNOSIS.md)'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;dataset'= {
            cand --spec 'The spec (TOML): faults, records per fault, model and ranges; an example with every key: config/dataset.toml'
            cand --out 'Output directory (created): dataset.npz, manifest.csv, spec.toml, and mcap/NNNNN/'
            cand --bearing 'Simulate this bearing instead of the spec''s `bearing`: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or a custom geometry. One spec makes the training set of every bearing''s model; the spec.toml written beside the set says the bearing used'
            cand --format 'Output format'
            cand --mcap 'Also write each record as a raw MCAP log (mcap/NNNNN/), replayable without a config'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;train'= {
            cand --dataset 'A directory written by `bearingd dataset` (dataset.npz and spec.toml); repeat it to train on several (same classes, and same bearing on shaft orders), e.g. a signal-model and a physics set'
            cand --out 'The model file to write (.safetensors)'
            cand --epochs 'Passes over the training segments'
            cand --seed 'The seed of the initial weights, the corruption noise and the batch order'
            cand --axis 'The input''s axis: `shaft` orders (the model knows the data set''s one bearing) or `fault-relative` orders (each fault''s own; the model serves any bearing, best trained on data sets of many, e.g. `bearing = "random"`)'
            cand --format 'Output format'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;calibrate'= {
            cand --channel 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)'
            cand --column 'Column of a CSV table: header name or 1-based index'
            cand --fs 'Sample rate in Hz (overrides what the file says)'
            cand --rpm 'Shaft speed in rpm (overrides what the file says)'
            cand --bearing 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"'
            cand --unit 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s'
            cand --fault 'The defect to model; default: the envelope diagnosis of the record'
            cand --band 'The band compared, as LO-HI in Hz; default: the band the envelope analysis chose for the fault'
            cand --load 'Radial load on the bearing, N'
            cand --dof 'The model: six degrees of freedom (seed 001) or five (seed 003)'
            cand --population 'Candidates per generation of the differential evolution'
            cand --generations 'Generations of the differential evolution'
            cand --simulated 'Seconds simulated per candidate'
            cand --seed 'Seed of the search: the same seed gives the same calibration'
            cand --plot 'Draw the measured, calibrated and default spectra to this file (.png or .svg)'
            cand --save 'Write the calibrated parameters as JSON (for `simulate --model physics --calibrated`)'
            cand --format 'Output format'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;evaluate'= {
            cand --recordings 'Instead of the simulator: every record of this manifest (CSV with a header: `file` relative to its folder, and `fault`, `note` or `life_frac` for the truth; `channel_var`, `fs_hz`, `rpm`, `bearing_geometry` where the file does not say) through `bearingd analyze` and through `bearingd import` + `replay`; writes recordings.json. May be given several times'
            cand --false-alarm-hours 'Instead of the sweep: H hours of healthy simulated signal per machine (the full sweep''s three machines at 0.6 and 1 × nominal speed, four noise levels, with the nuisance) streamed through the daemon''s channel monitor; counts the fault flags that rise (false alarms) per hour of operation; writes false_alarms.json and false_alarms.txt. Without a value: 2 h per machine (about 2.5 min of CPU)'
            cand --out 'Directory for results.json, results.csv, table.txt and pd_vs_snr.svg (with --recordings: recordings.json and recordings.txt) (created)'
            cand --seed 'Seed of the sweep: the same seed gives the same records and results'
            cand --jobs 'Worker threads (default: the machine''s cores)'
            cand --config 'Take the analysis and threshold settings from this config file instead of the embedded default (to evaluate a tuned configuration). With `twin.learned_model` the sweep''s record path also writes agreement_grid.txt (the learned model''s agreement decided at every point of a parameter grid); with --recordings only its agreement_* keys and model are used, by both paths'
            cand --format 'Output format'
            cand --all-channels 'With --recordings: also the other channels of each record (CWRU fan end and base, every axis of other files; IMS snapshots are always evaluated on all eight)'
            cand --strict 'With --recordings: exit 1 if any answer is confident and wrong, the paths disagree on any record, or any record fails (CI)'
            cand --quick 'The small sweep CI runs (both bearings at nominal speed, default severity, the simulator''s default noise and 0 dB SNR, healthy records) instead of the full one'
            cand --no-nuisance 'Leave out the machine''s nuisance (shaft harmonics, modulated noise, random impulses, gear and electrical tones): bearing, 1× tone and white noise only'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;trend'= {
            cand --channel 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)'
            cand --column 'Column of a CSV table: header name or 1-based index'
            cand --fs 'Sample rate in Hz (overrides what the file says)'
            cand --rpm 'Shaft speed in rpm (overrides what the file says)'
            cand --bearing 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"'
            cand --unit 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s'
            cand --format 'Output format'
            cand --plot 'Draw the stage timeline (RMS with the trend, kurtosis, HW residual, fault score) to this file (.png or .svg)'
            cand --baseline 'Snapshots that form the healthy baseline (and the aging baseline of RMS)'
            cand --smoothing 'Running median over this many snapshots before the tracker (1: none)'
            cand --sigma 'Standard deviations above a baseline that change the stage'
            cand --trend-window 'Snapshots in the sliding window of the RMS trend'
            cand --threshold-g 'RMS threshold in g for the time-to-threshold (default: the failure limit the tracker learns at the start of degradation)'
            cand --interval 'Seconds between snapshots whose names state no time (.mcap and .wav files; given this, any other file too, e.g. CSV tables), placed in name order'
            cand --window 'Records longer than 1.5 windows (IMS, MCAP logs) are cut into windows of this many seconds, each one snapshot'
            cand --no-hw 'Do not identify the HW model per snapshot'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;analyze'= {
            cand --channel 'Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log)'
            cand --column 'Column of a CSV table: header name or 1-based index'
            cand --fs 'Sample rate in Hz (overrides what the file says)'
            cand --rpm 'Shaft speed in rpm (overrides what the file says)'
            cand --bearing 'Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0"'
            cand --unit 'Unit of the file''s values, for WAV, plain CSV and .mat files (default: g; for an integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no velocity in mm/s'
            cand --format 'Output format'
            cand --plot 'Draw the envelope spectrum and the kurtogram to this file (.png or .svg); with several records, the record''s file name is added before the extension. Runs in bearingd-lab'
            cand --config 'Take the analysis settings from this configuration file''s [analysis] section, and its twin.learned_model unless --learned is given: the daemon''s decision, offline'
            cand --band-selection 'How to choose the resonance band'
            cand --band 'The band for --band-selection fixed, as LO-HI in Hz, e.g. 2000-4000'
            cand --window 'Envelope-spectrum window length in seconds (rounded to a power of two samples)'
            cand --learned 'Add a learned model''s opinion: a .safetensors file of `bearingd train`, or a directory of them, one per bearing (the shipped ones: models/, one for each catalog bearing). It may settle what the envelope leaves open, never overrule it; the JSON gains `learned`'
            cand --machine-group 'ISO 10816-3 machine group for the velocity zones: 1 (above 300 kW, or shaft height from 315 mm) or 2 (15 to 300 kW, shaft height 160 to 315 mm)'
            cand --foundation 'Foundation for the velocity zones: rigid or flexible'
            cand --hw-states 'With --hw: where the median filter sits in the virtual states'' chain of differences, raw_once (the raw signal, once: the seed''s reading) or each_order (every order''s output on its own); docs/HW.md compares them'
            cand --demo 'Analyse a built-in simulated record (outer-race fault, SKF 6205-2RS, 1772 rpm, 12 kHz)'
            cand --no-refine 'Do not refine the band per fault hypothesis by its fault-band SNR'
            cand --twin 'Also fit the signal-model twin for each fault hypothesis (adds `twin` to the JSON, the twin''s spectrum to the text and the plot)'
            cand --hw 'Instead of the diagnosis: identify the Hammerstein–Wiener model (seed 003) for state orders 0…9 on each record and print its accuracy and time per order, and the mean per directory (bearing)'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;completions'= {
            cand --program 'Whose command line: bearingd (the service) or bearingd-lab'
            cand --out 'Write every shell''s script of both programs into this directory (docs/cli/completions is where the service''s scripts are taken from; `make cli-docs` writes it)'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'bearingd-lab;man'= {
            cand --out 'The directory to write the pages into (created if absent): bearingd.1, bearingd-analyze.1, ..., bearingd-lab.1, bearingd-lab-train.1, ...'
            cand -h 'Print help'
            cand --help 'Print help'
        }
        &'bearingd-lab;help'= {
            cand simulate 'Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV'
            cand dataset 'Generate a labelled synthetic data set (signal model or physics twin) for learned diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log'
            cand train 'Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of `bearingd dataset`; writes a model file for `analyze --learned`'
            cand calibrate 'Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width) to a measured record; prints the parameters and the fit error, plots the spectra'
            cand evaluate 'Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records) through the real pipeline: detection probability, false alarms, confusion matrix, plot; or real recordings of a manifest through `analyze` and through the daemon'
            cand trend 'Follow a bearing''s life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV and CSV with --interval): health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its time to the failure limit; text, JSON or a table, and a plot'
            cand analyze 'Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the kurtogram with --plot (`bearingd analyze --plot` runs this)'
            cand completions 'Print the shell completion script of bearingd-lab (or, with --program bearingd, of the service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all'
            cand man 'Write the man pages of bearingd and bearingd-lab and of each of their commands into a directory (`make install` installs the committed ones, docs/cli/man)'
            cand help 'Print this message or the help of the given subcommand(s)'
        }
        &'bearingd-lab;help;simulate'= {
        }
        &'bearingd-lab;help;dataset'= {
        }
        &'bearingd-lab;help;train'= {
        }
        &'bearingd-lab;help;calibrate'= {
        }
        &'bearingd-lab;help;evaluate'= {
        }
        &'bearingd-lab;help;trend'= {
        }
        &'bearingd-lab;help;analyze'= {
        }
        &'bearingd-lab;help;completions'= {
        }
        &'bearingd-lab;help;man'= {
        }
        &'bearingd-lab;help;help'= {
        }
    ]
    $completions[$command]
}
