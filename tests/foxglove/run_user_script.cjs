// Runs a Foxglove User Script on messages, as Foxglove would: type-checks it (strict) against a
// stand-in for the `./types` module Foxglove generates, compiles it with TypeScript, then calls
// its default export once per input message.
//
//   node run_user_script.cjs SCRIPT.ts < messages.jsonl > outputs.jsonl
//
// Input lines: {"topic", "log_time", "message"}; a raw block's `first_sample` comes as a decimal
// string and is handed to the script as a BigInt (Foxglove decodes protobuf uint64 so). Output
// lines: {"topic", "log_time", "message"} for each message the script returns. The script's
// `inputs` choose which input lines it sees. Exit 1 on a type error or a throw.
"use strict";
const fs = require("fs");
const path = require("path");
const ts = require("typescript");

// What Foxglove's generated `./types` gives a script reading bearingd's raw blocks.
const TYPES = `
export type Time = { sec: number; nsec: number };
type ChannelId = { sensor: string; axis: string };
type RawBlock = {
  channel: ChannelId;
  first_sample: bigint;
  sample_rate_hz: number;
  scale_g_per_count: number;
  counts: Int32Array;
};
export type Input<T extends string> = { topic: T; receiveTime: Time; message: RawBlock };
`;

function typeCheck(file, source) {
  const options = { strict: true, noEmit: true, target: ts.ScriptTarget.ES2020, lib: ["lib.es2020.d.ts"] };
  const host = ts.createCompilerHost(options);
  const files = { [path.resolve("script.ts")]: source, [path.resolve("types.ts")]: TYPES };
  const getSourceFile = host.getSourceFile;
  host.getSourceFile = (name, version) =>
    name in files
      ? ts.createSourceFile(name, files[name], version)
      : getSourceFile.call(host, name, version);
  const fileExists = host.fileExists;
  host.fileExists = (name) => name in files || fileExists.call(host, name);
  const program = ts.createProgram([path.resolve("script.ts")], options, host);
  const problems = ts.getPreEmitDiagnostics(program);
  for (const d of problems) {
    const text = ts.flattenDiagnosticMessageText(d.messageText, "\n");
    console.error(`${file}: ${text}`);
  }
  return problems.length === 0;
}

function load(source) {
  const js = ts.transpileModule(source, {
    compilerOptions: { module: ts.ModuleKind.CommonJS, target: ts.ScriptTarget.ES2020 },
  }).outputText;
  const module = { exports: {} };
  new Function("module", "exports", "require", js)(module, module.exports, () => ({}));
  return module.exports;
}

function main() {
  const file = process.argv[2];
  const source = fs.readFileSync(file, "utf8");
  if (!typeCheck(file, source)) process.exit(1);
  const script = load(source);
  const inputs = new Set(script.inputs);
  const lines = fs.readFileSync(0, "utf8").split("\n").filter((l) => l.trim() !== "");
  const out = [];
  for (const line of lines) {
    const event = JSON.parse(line);
    if (!inputs.has(event.topic)) continue;
    const message = { ...event.message, first_sample: BigInt(event.message.first_sample) };
    message.counts = Int32Array.from(message.counts);
    const ns = BigInt(event.log_time);
    const receiveTime = { sec: Number(ns / 1000000000n), nsec: Number(ns % 1000000000n) };
    const result = script.default({ topic: event.topic, receiveTime, message });
    if (result !== undefined) {
      out.push(JSON.stringify({ topic: script.output, log_time: event.log_time, message: result }));
    }
  }
  process.stdout.write(out.join("\n") + (out.length ? "\n" : ""));
}

main();
