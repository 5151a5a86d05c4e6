// encoder_channel: one encoder (A and B pins) from the pins to the captured window.
//
// input_conditioner x2 -> quadrature_decoder -> window_counter, plus the per-channel illegal
// transition counter (OMNILOC_ERROR_COUNT_BITS wide, saturating, never cleared except by reset:
// the host needs to know that a channel has a fault, not how many thousands).
// Latency from a pin change to the count: conditioner (3 cycles, or FILTER + 2 when FILTER > 1)
// + decoder (1 cycle); a pulse of the decoder is in the window whose capture_i is at or after it.
//
// Assumptions: a_i/b_i asynchronous; filter_len_i, mode_i and en_i from the register file
// (mode_i never 3); capture_i one-cycle pulses. rst_i synchronous, active high.
// Guarantees (proven end to end, at W = 3 so that the counts wrap): every legal step of the
// conditioned A/B levels that the mode counts while enabled is in exactly one window: the sum of
// all captured window counts plus the running count equals the steps counted by a reference
// (mod 2^W); each captured count equals the reference's steps in that window.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module encoder_channel #(
    // counts and positions wrap at 2^W (the error count is ERROR_COUNT_BITS wide, saturating)
    parameter integer W = `OMNILOC_DATA_W
) (
    input  wire                                 clk_i,
    input  wire                                 rst_i,
    input  wire                                 a_i,
    input  wire                                 b_i,
    input  wire [`OMNILOC_FILTER_LENGTH_W-1:0]  filter_len_i,
    input  wire                                 en_i,
    input  wire [`OMNILOC_CONTROL_DECODE_W-1:0] mode_i,
    input  wire                                 capture_i,
    output wire [W-1:0]                         win_count_o,
    output wire [W-1:0]                         win_position_o,
    output wire                                 win_dir_o,
    output wire [W-1:0]                         position_o,
    output wire                                 dir_o,
    // One-cycle pulse per illegal transition, and their saturating count.
    output wire                                 err_o,
    output wire [`OMNILOC_ERROR_COUNT_BITS-1:0] err_count_o
);

localparam integer DATA_W = W;
localparam integer ERR_W = `OMNILOC_ERROR_COUNT_BITS;

wire a_clean;
wire b_clean;
wire a_valid;
wire b_valid;
wire up;
wire down;

input_conditioner #(.LEN_W(`OMNILOC_FILTER_LENGTH_W)) u_cond_a (
    .clk_i(clk_i), .rst_i(rst_i), .in_i(a_i), .len_i(filter_len_i),
    .out_o(a_clean), .valid_o(a_valid)
);

input_conditioner #(.LEN_W(`OMNILOC_FILTER_LENGTH_W)) u_cond_b (
    .clk_i(clk_i), .rst_i(rst_i), .in_i(b_i), .len_i(filter_len_i),
    .out_o(b_clean), .valid_o(b_valid)
);

quadrature_decoder u_dec (
    .clk_i(clk_i), .rst_i(rst_i), .a_i(a_clean), .b_i(b_clean),
    .valid_i(a_valid & b_valid), .en_i(en_i), .mode_i(mode_i),
    .up_o(up), .down_o(down), .dir_o(dir_o), .err_o(err_o)
);

window_counter #(.W(DATA_W)) u_win (
    .clk_i(clk_i), .rst_i(rst_i), .up_i(up), .down_i(down), .dir_i(dir_o),
    .capture_i(capture_i), .win_count_o(win_count_o), .win_position_o(win_position_o),
    .win_dir_o(win_dir_o), .position_o(position_o)
);

reg [ERR_W-1:0] err_count_q;
assign err_count_o = err_count_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        err_count_q <= {ERR_W{1'b0}};
    end else if (err_o && err_count_q != {ERR_W{1'b1}}) begin
        err_count_q <= err_count_q + 1'b1;
    end
end

`ifdef FORMAL
// End to end, from the conditioned A/B levels to the window counts, against a reference that
// never looks at the decoder's up/down pulses: it derives each step from the A/B levels the
// decoder is given (as the decoder's own proof does) and counts it through the same pipeline.
// The submodules' own properties are part of this proof (their asserts help the induction close);
// so are their assumptions: a constant filter length of at most 6 (input_conditioner), never up
// and down together (window_counter; the decoder's proof asserts it).
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);
// The register file never lets the reserved decode mode 3 through.
always @(*) assume (mode_i != 2'd3);

// The previous conditioned levels (reset to 00, as the decoder's phase) and whether both
// conditioners have delivered a valid level yet.
reg f_a_q = 1'b0;
reg f_b_q = 1'b0;
reg f_primed_q = 1'b0;
always @(posedge clk_i) begin
    if (rst_i) begin
        f_a_q <= 1'b0;
        f_b_q <= 1'b0;
        f_primed_q <= 1'b0;
    end else begin
        f_a_q <= a_clean;
        f_b_q <= b_clean;
        f_primed_q <= f_primed_q | (a_valid & b_valid);
    end
end

// The step this sample makes: legal when exactly one level changed, forward when A leads B;
// counted in X4 always, in X2 on A edges, in X1 on A edges while B is low; only while enabled.
wire f_a_ch = a_clean != f_a_q;
wire f_b_ch = b_clean != f_b_q;
wire f_fwd = f_a_ch ? (a_clean != b_clean) : (a_clean == b_clean);
wire f_counted = (f_a_ch != f_b_ch) && en_i && f_primed_q
              && ((mode_i == `OMNILOC_CONTROL_DECODE_X1) ? (f_a_ch && !b_clean)
                : (mode_i == `OMNILOC_CONTROL_DECODE_X2) ? f_a_ch : 1'b1);
wire [W-1:0] f_step = !f_counted ? {W{1'b0}} : (f_fwd ? {{(W-1){1'b0}}, 1'b1} : {W{1'b1}});

// The reference, one cycle behind the sample (the decoder's latency): f_pend_q is the step the
// window counter is given this cycle; f_ref_q every step since reset, f_run_q those of the running
// window, f_last_q those of the last captured window (a step in the capture cycle is in the
// ending window). f_sum_q adds up every captured window count read from win_count_o, once each
// (in the cycle after its capture, f_cap_q); f_captured is that sum with the newest window.
reg [W-1:0] f_pend_q = {W{1'b0}};
reg [W-1:0] f_ref_q = {W{1'b0}};
reg [W-1:0] f_run_q = {W{1'b0}};
reg [W-1:0] f_last_q = {W{1'b0}};
reg [W-1:0] f_sum_q = {W{1'b0}};
reg         f_cap_q = 1'b0;
// No backward step since reset (for the wrap covers).
reg         f_fwd_only_q = 1'b1;
always @(posedge clk_i) begin
    if (rst_i) begin
        f_pend_q <= {W{1'b0}};
        f_ref_q <= {W{1'b0}};
        f_run_q <= {W{1'b0}};
        f_last_q <= {W{1'b0}};
        f_sum_q <= {W{1'b0}};
        f_cap_q <= 1'b0;
        f_fwd_only_q <= 1'b1;
    end else begin
        f_pend_q <= f_step;
        f_ref_q <= f_ref_q + f_pend_q;
        f_cap_q <= capture_i;
        if (f_cap_q) f_sum_q <= f_sum_q + win_count_o;
        if (capture_i) begin
            f_last_q <= f_run_q + f_pend_q;
            f_run_q <= {W{1'b0}};
        end else begin
            f_run_q <= f_run_q + f_pend_q;
        end
        if (f_pend_q == {W{1'b1}}) f_fwd_only_q <= 1'b0;
    end
end
wire [W-1:0] f_captured = f_sum_q + (f_cap_q ? win_count_o : {W{1'b0}});
// The live count, not yet captured.
wire [W-1:0] f_live = position_o - win_position_o;

always @(*) begin
    if (f_past_valid && !rst_i) begin
        // Conservation across every capture: nothing lost, nothing counted twice (mod 2^W).
        assert (f_captured + f_live == f_ref_q);
        // Each captured window holds exactly the steps made in it, the running one those since.
        assert (win_count_o == f_last_q);
        assert (f_live == f_run_q);
        // The captured position is the sum of the captured windows; the live one every step.
        assert (win_position_o == f_captured);
        assert (position_o == f_ref_q);
    end
end

// Each property reachable: a capture of a non-zero window, of a negative one, a capture in the
// same cycle as a step (the step counted in the ending window), the position wrapping past 2^W - 1
// just after a capture; forward steps only: the running count wrapping from the largest positive
// value to the most negative one in one window, the sum of the captured windows doing so across a
// capture (2^(W-1) forward steps each).
localparam [W-1:0] F_MAX = {1'b0, {(W-1){1'b1}}};
localparam [W-1:0] F_MIN = {1'b1, {(W-1){1'b0}}};
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (f_cap_q && win_count_o == {{(W-2){1'b0}}, 2'd2});
        cover (f_cap_q && win_count_o == {W{1'b1}});
        cover (f_cap_q && $past(f_pend_q) != {W{1'b0}} && win_count_o != {W{1'b0}});
        cover (f_cap_q && position_o == {W{1'b0}} && $past(position_o) == {W{1'b1}});
        cover (f_fwd_only_q && !$past(capture_i) && f_live == F_MIN && $past(f_live) == F_MAX);
        cover (f_fwd_only_q && f_cap_q && f_sum_q != {W{1'b0}} && f_captured == F_MIN && $past(f_captured) == F_MAX);
    end
end
`endif

endmodule

`resetall
