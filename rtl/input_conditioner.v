// input_conditioner: one asynchronous encoder pin -> a clean, synchronous level.
//
// Two-flip-flop synchronizer, then a run-length glitch filter: the output takes a new level only
// after the synchronized input has shown it for len_i consecutive cycles, so a pulse shorter than
// len_i cycles never reaches the decoder and a level held at least len_i cycles always does.
// len_i = 0 and len_i = 1 both mean "off" (every synchronized level passes).
// Latency from the pin to out_o: 3 cycles for len_i <= 1, len_i + 2 cycles otherwise.
// (A pin level sampled at clock edge t is on out_o after edge t + 1 + max(len_i, 1).)
//
// After reset the output is not derived from a transition: once the synchronizer holds a real
// sample, out_o is loaded with it directly and valid_o rises (3 cycles after reset), so a pin that is high at
// power-up never looks like an edge.
//
// Assumptions: in_i is asynchronous (hence the synchronizer); len_i may change at any time
// (a change takes effect on the run being measured); rst_i synchronous, active high.
// Guarantees (proven): out_o only changes to a level the synchronizer has held for
// max(len_i, 1) consecutive cycles; it follows the input when the filter is off.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module input_conditioner #(
    parameter integer LEN_W = `OMNILOC_FILTER_LENGTH_W   // width of FILTER.LENGTH
) (
    input  wire             clk_i,
    input  wire             rst_i,
    input  wire             in_i,
    input  wire [LEN_W-1:0] len_i,
    output wire             out_o,
    output wire             valid_o
);

(* ASYNC_REG = "TRUE" *) reg sync1_q;
(* ASYNC_REG = "TRUE" *) reg sync2_q;
reg [2:0]       prime_q;
reg             out_q;
reg [LEN_W-1:0] run_q;

assign out_o = out_q;
assign valid_o = prime_q[2];

// run_q counts the cycles the synchronized input has differed from out_q, minus one.
wire differs = (sync2_q != out_q);
// The filter length, decoded once a cycle into registers (FILTER fans out to all eight
// conditioners; a subtract and compare behind that fan-out kept the iCE40 build slow).
// settled_q: the level differing now has held long enough (or the filter is off), i.e.
// len <= 1 || run_q >= len - 1, computed a cycle ahead from the run this cycle makes (0, or
// run_q + 1: run_q + 1 >= len - 1 is run_q >= len - 2), so no compare sits between run_q and the
// decision. So a new length takes effect two cycles after it is written. '>=' (not '==') so that
// shortening the filter in mid-run never strands a run past its end.
localparam [LEN_W-1:0] ONE = {{(LEN_W-1){1'b0}}, 1'b1};
reg             off_q;     // len_i <= 1: the filter is off
reg [LEN_W-1:0] lm2_q;     // len_i - 2
always @(posedge clk_i) begin
    off_q <= (len_i <= ONE);
    lm2_q <= len_i - (ONE + ONE);
end
reg  settled_q;
wire settled = settled_q;

// The run grows this cycle (the last branch below).
wire grows = !rst_i && prime_q[2] && differs && !settled;
always @(posedge clk_i) settled_q <= off_q || (grows && (run_q >= lm2_q));

always @(posedge clk_i) begin
    if (rst_i) begin
        sync1_q <= 1'b0;
        sync2_q <= 1'b0;
        prime_q <= 3'b000;
        out_q <= 1'b0;
        run_q <= {LEN_W{1'b0}};
    end else begin
        sync1_q <= in_i;
        sync2_q <= sync1_q;
        prime_q <= {prime_q[1:0], 1'b1};
        if (!prime_q[2]) begin
            // sync2_q holds the first real pin sample once prime_q[1] is set; loading it here
            // (and before, harmlessly) makes the first valid level an initial state, not an edge.
            out_q <= sync2_q;
            run_q <= {LEN_W{1'b0}};
        end else if (!differs) begin
            run_q <= {LEN_W{1'b0}};
        end else if (settled) begin
            out_q <= sync2_q;
            run_q <= {LEN_W{1'b0}};
        end else begin
            run_q <= run_q + {{(LEN_W-1){1'b0}}, 1'b1};
        end
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
wire [LEN_W-1:0] f_lm2 = len_i - (ONE + ONE);
reg f_past2_valid = 1'b0;
always @(posedge clk_i) f_past2_valid <= f_past_valid;
initial assume (rst_i);

// Independent measure: consecutive cycles (up to saturation) that sync2_q has held its value.
reg [LEN_W:0] f_held = 0;
always @(posedge clk_i) begin
    if (rst_i) f_held <= 0;
    else if (sync1_q != sync2_q) f_held <= 1;
    else if (f_held != {(LEN_W+1){1'b1}}) f_held <= f_held + 1'b1;
end

// The filter length is held constant during a run in this proof (the RTL tolerates changes,
// but "held len_i cycles" is only well defined for a constant len_i).
reg [LEN_W-1:0] f_len_q = 0;
always @(posedge clk_i) f_len_q <= len_i;
always @(*) begin
    if (f_past_valid) assume (len_i == f_len_q);
    assume (len_i <= 6);
end

always @(*) begin
    // The decoded length and settled_q are what they replace (auxiliary invariants; len_i is
    // constant here, and the decode needs two cycles after the start).
    if (f_past_valid) assert (off_q == (len_i <= 1) && lm2_q == f_lm2);
    if (f_past2_valid && !rst_i)
        assert (settled_q == ((len_i <= 1) || ({1'b0, run_q} + 1'b1 >= {1'b0, len_i})));
    if (f_past_valid && !rst_i && prime_q[2]) begin
        // run_q is the run length of the differing level minus one, bounded by the filter.
        if (differs && len_i > 1) assert ({1'b0, run_q} + 1'b1 == f_held);
        if (len_i <= 1) assert (run_q == 0);
        if (len_i > 1) assert (run_q < len_i);
    end
    if (f_past_valid && !rst_i) begin
        assert (prime_q == 3'b000 || prime_q == 3'b001 || prime_q == 3'b011 || prime_q == 3'b111);
        if (!prime_q[2]) assert (run_q == 0);
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i && $past(prime_q[2])) begin
        // A change of out_o is always to the synchronized level ...
        if (out_q != $past(out_q)) begin
            assert (out_q == $past(sync2_q));
            // ... and only once that level has held for max(len, 1) cycles.
            assert ($past(f_held) >= (($past(len_i) > 1) ? $past(len_i) : 1));
        end
        // With the filter off the output follows the synchronizer with one cycle of delay.
        if ($past(len_i) <= 1) assert (out_q == $past(sync2_q));
        // A level held for the filter length always passes.
        if ($past(differs) && $past(f_held) >= (($past(len_i) > 1) ? $past(len_i) : 1))
            assert (out_q == $past(sync2_q));
    end
end

// Each property reachable: a level passing the filter of length 3, a glitch of 2 cycles held back
// by it, a level passing with the filter off.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i && $past(prime_q[2])) begin
        cover (out_q != $past(out_q) && $past(len_i) == 3);
        cover ($past(len_i) == 3 && $past(f_held) == 2 && $past(sync1_q) != $past(sync2_q)
               && $past(differs) && out_q == $past(out_q));
        cover (out_q != $past(out_q) && $past(len_i) == 0);
    end
end
`endif

endmodule

`resetall
