// Foxglove User Script (embedded in bearingd.layout.json; this file is its source, kept in
// sync by tests/python/foxglove_layout.py): publishes each raw block of /raw/motor-de/radial in
// g, with the time of each sample in seconds of sample time, so that a Plot panel draws the
// waveform in g against time. The log keeps the sensor's integer counts (lossless and 2.2x
// smaller than a float field: docs/MCAP.md, "Raw samples in g"); g = count x scale_g_per_count.
// For another channel, change the two topic names below.
import { Input } from "./types";

export const inputs = ["/raw/motor-de/radial"];
export const output = "/studio_script/raw_g/motor-de/radial";

type RawInG = {
  first_sample: number;
  sample_rate_hz: number;
  t_s: number[];
  g: number[];
};

export default function script(event: Input<"/raw/motor-de/radial">): RawInG {
  const block = event.message;
  const first = Number(block.first_sample);
  const fs = block.sample_rate_hz;
  const scale = block.scale_g_per_count;
  const t_s: number[] = [];
  const g: number[] = [];
  for (let i = 0; i < block.counts.length; i++) {
    t_s.push((first + i) / fs);
    g.push(block.counts[i] * scale);
  }
  return { first_sample: first, sample_rate_hz: fs, t_s, g };
}
