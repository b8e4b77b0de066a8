function results = bench_process(samples, repeats)
%BENCH_PROCESS Per-sample cost of the compensators called from MATLAB/Octave.
%   bench_process() times, for Table 1 (10 operators, f64) and each method, a whole trajectory
%   of 100 000 samples through c.process (the median of 15 runs, in ns per sample), the same
%   through the gateway without the class (hystcomp_mex directly), and 10 000 calls of c.step
%   and of the gateway's step (per call). Compare with `hystcomp bench` and `cargo bench -p hystcomp-core` (README.md).
%   bench_process(SAMPLES, REPEATS) sets the trajectory's length and the number of runs.
%
%   Build the MEX file against the release library first (build.m). Not run by the tests:
%   speed is measured in benchmarks, not asserted.
if nargin < 1, samples = 100000; end
if nargin < 2, repeats = 15; end
here = fileparts(mfilename('fullpath'));
root = fullfile(here, '..', '..', '..');
plant = hystcomp.load_model(fullfile(root, 'models', 'table1-plant.json'));
inverse = hystcomp.load_model(fullfile(root, 'models', 'table2-inverse.json'));
% One period of a 1 Hz cosine from rest, within 10 .. 65 um (reachable: nothing saturates).
t = (0:samples - 1)' / samples;
yd = 10 + 27.5 * (1 - cos(2 * pi * t));
% The third column allows the plain one-sample-delayed loop where the model's loop gain can
% reach 1 (Table 1's WIHC: 1.66), as the Rust benches time it; the guarded loops are the safe
% form of the delayed ones.
methods = {'ihc', plant, false; 'ihc-delayed', plant, false; 'ihc-guarded', plant, false; ...
           'wihc', plant, false; 'wihc-delayed', plant, true; 'wihc-guarded', plant, false; ...
           'dihc', inverse, false};
steps = min(samples, 10000);
results = struct('method', {}, 'process_ns', {}, 'gateway_ns', {}, 'step_ns', {}, ...
                 'gateway_step_ns', {});
fprintf('%-13s %12s %12s %12s %12s   (ns per sample, median of %d runs of %d samples)\n', ...
        'method', 'c.process', 'mex process', 'c.step', 'mex step', repeats, samples);
for k = 1:size(methods, 1)
    c = hystcomp.Compensator(methods{k, 2}, methods{k, 1}, [], ...
                             'AllowUnstableDelay', methods{k, 3});
    id = hystcomp_mex('compensator_new', methods{k, 2}, methods{k, 1}, [], methods{k, 3});
    process = zeros(repeats, 1);
    gateway = zeros(repeats, 1);
    step = zeros(repeats, 1);
    gateway_step = zeros(repeats, 1);
    c.process(yd); % warm up
    for r = 1:repeats
        c.reset();
        start = tic(); c.process(yd); process(r) = toc(start);
        hystcomp_mex('compensator_reset', id);
        start = tic(); hystcomp_mex('compensator_process', id, yd); gateway(r) = toc(start);
        c.reset();
        start = tic();
        for s = 1:steps
            c.step(yd(s));
        end
        step(r) = toc(start);
        hystcomp_mex('compensator_reset', id);
        start = tic();
        for s = 1:steps
            hystcomp_mex('compensator_step', id, yd(s));
        end
        gateway_step(r) = toc(start);
    end
    hystcomp_mex('compensator_free', id);
    delete(c);
    results(k).method = methods{k, 1};
    results(k).process_ns = median(process) / samples * 1e9;
    results(k).gateway_ns = median(gateway) / samples * 1e9;
    results(k).step_ns = median(step) / steps * 1e9;
    results(k).gateway_step_ns = median(gateway_step) / steps * 1e9;
    fprintf('%-13s %12.1f %12.1f %12.0f %12.0f\n', results(k).method, results(k).process_ns, ...
            results(k).gateway_ns, results(k).step_ns, results(k).gateway_step_ns);
end
end
