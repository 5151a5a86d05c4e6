// window_counter: per-channel window count, capture at the tick, and the position accumulator.
//
// Counts up_i/down_i pulses into the running window. At capture_i the ending window's count is
// copied out and the counter restarts in the same clock edge. A pulse present in the capture
// cycle belongs to the ENDING window (it is added to the captured value and the counter restarts
// at zero), so no edge is lost or counted twice. The position is kept once: base_q, the position
// at the start of the last captured window, which adds that window's count at the next capture
// (never cleared, wraps at 2^W); win_position_o = base_q + win_count_q, so every adder starts and
// ends at flip-flops (no carry chain behind another). A host that misses a window still recovers
// the position as the difference of two captured positions. position_o (the live position) is
// win_position_o plus the running count, for other tops (the core leaves it unconnected).
//
// Assumptions: up_i and down_i are never high together (quadrature_decoder guarantees it);
// rst_i synchronous, active high.
// Guarantees (proven by k-induction): position == captured position + running count at all times
// (conservation: nothing lost or doubled across a capture); each captured count equals the
// difference of consecutive captured positions; the position moves by exactly the pulse.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module window_counter #(
    parameter integer W = `OMNILOC_DATA_W   // the register width: counts and positions wrap at 2^W
) (
    input  wire         clk_i,
    input  wire         rst_i,
    input  wire         up_i,
    input  wire         down_i,
    input  wire         dir_i,
    input  wire         capture_i,
    // Signed count of the last captured window, its end position and direction.
    output wire [W-1:0] win_count_o,
    output wire [W-1:0] win_position_o,
    output wire         win_dir_o,
    // Live position accumulator.
    output wire [W-1:0] position_o
);

// The running count in two halves, so that no carry chain is W bits long: the high half moves
// when the low half wraps, told by two flags kept in step with the low half (lo_ones_q: low half
// all ones, lo_zero_q: all zeros), registered so that they cost no logic in front of the high half.
localparam integer LO_W = W / 2;
localparam integer HI_W = W - LO_W;
reg [LO_W-1:0] lo_q;
reg [HI_W-1:0] hi_q;
reg            lo_ones_q;
reg            lo_zero_q;
wire [W-1:0] count_q = {hi_q, lo_q};
reg [W-1:0] win_count_q;
reg [W-1:0] base_q;
reg         win_dir_q;

assign win_count_o = win_count_q;
assign win_position_o = base_q + win_count_q;
assign win_dir_o = win_dir_q;
assign position_o = win_position_o + count_q;

// The ending window's count (this cycle's pulse included), half by half.
wire [LO_W-1:0] lo_end = lo_q + (up_i ? {{(LO_W-1){1'b0}}, 1'b1} : (down_i ? {LO_W{1'b1}} : {LO_W{1'b0}}));
wire hi_inc = up_i && lo_ones_q;
wire hi_dec = down_i && lo_zero_q;
wire [HI_W-1:0] hi_end = hi_q + (hi_inc ? {{(HI_W-1){1'b0}}, 1'b1} : (hi_dec ? {HI_W{1'b1}} : {HI_W{1'b0}}));
wire [W-1:0] ending = {hi_end, lo_end};
localparam [LO_W-1:0] LO_ONE = {{(LO_W-1){1'b0}}, 1'b1};
localparam [LO_W-1:0] LO_ONES = {LO_W{1'b1}};
// The flags of lo_end, from lo_q and the pulse (no carry chain in front of them).
wire end_ones = up_i ? (lo_q == LO_ONES - LO_ONE) : (down_i ? lo_zero_q : lo_ones_q);
wire end_zero = up_i ? lo_ones_q : (down_i ? (lo_q == LO_ONE) : lo_zero_q);

always @(posedge clk_i) begin
    if (rst_i) begin
        lo_q <= {LO_W{1'b0}};
        hi_q <= {HI_W{1'b0}};
        lo_ones_q <= 1'b0;
        lo_zero_q <= 1'b1;
        win_count_q <= {W{1'b0}};
        base_q <= {W{1'b0}};
        win_dir_q <= 1'b0;
    end else begin
        if (capture_i) begin
            win_count_q <= ending;
            base_q <= base_q + win_count_q;
            win_dir_q <= dir_i;
            lo_q <= {LO_W{1'b0}};
            hi_q <= {HI_W{1'b0}};
            lo_ones_q <= 1'b0;
            lo_zero_q <= 1'b1;
        end else begin
            lo_q <= lo_end;
            hi_q <= hi_end;
            lo_ones_q <= end_ones;
            lo_zero_q <= end_zero;
        end
    end
end

`ifdef FORMAL
// +1, -1 or 0 as a W-bit two's-complement step.
wire [W-1:0] delta = up_i ? {{(W-1){1'b0}}, 1'b1} : (down_i ? {W{1'b1}} : {W{1'b0}});
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);
always @(*) assume (!(up_i && down_i));

// Captured position of the window before the last one, and an independent position accumulator
// that adds every pulse.
reg [W-1:0] f_prev_win_position = {W{1'b0}};
reg [W-1:0] f_position = {W{1'b0}};
always @(posedge clk_i) begin
    if (rst_i) begin
        f_prev_win_position <= {W{1'b0}};
        f_position <= {W{1'b0}};
    end else begin
        f_position <= f_position + delta;
        if (capture_i) f_prev_win_position <= win_position_o;
    end
end

always @(*) begin
    if (f_past_valid && !rst_i) begin
        // Conservation: every pulse is in exactly one place, the last window or the running one.
        assert (f_position == win_position_o + count_q);
        // The flags describe the low half (what the split count relies on).
        assert (lo_ones_q == (lo_q == LO_ONES));
        assert (lo_zero_q == (lo_q == {LO_W{1'b0}}));
        assert (position_o == f_position);
        assert (win_count_q == win_position_o - f_prev_win_position);
        assert (base_q == f_prev_win_position);
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // The position moves by exactly the pulse of the previous cycle.
        assert (position_o == $past(position_o) + $past(delta));
        if ($past(capture_i)) begin
            // Across the capture: window count + new counter = edges seen.
            assert (win_count_q + count_q == $past(count_q) + $past(delta));
            assert (count_q == {W{1'b0}});
            // The window's direction is the decoder's at the capture.
            assert (win_dir_q == $past(dir_i));
        end else begin
            assert (count_q == $past(count_q) + $past(delta));
            assert (win_count_q == $past(win_count_q));
            assert (win_dir_q == $past(win_dir_q));
        end
    end
end

// Each property reachable: a capture with a pulse in its cycle (both ways), a negative window,
// a window ending forward and one ending backward, the position moving back past zero.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover ($past(capture_i) && $past(up_i) && win_count_q == {{(W-2){1'b0}}, 2'd2});
        cover ($past(capture_i) && $past(down_i) && win_count_q == {W{1'b1}});
        cover ($past(capture_i) && win_dir_q && win_count_q == {W{1'b1}});
        cover ($past(capture_i) && !win_dir_q && win_count_q == {{(W-1){1'b0}}, 1'b1});
        cover (position_o == {W{1'b1}} && $past(position_o) == {W{1'b0}});
    end
end
`endif

endmodule

`resetall
