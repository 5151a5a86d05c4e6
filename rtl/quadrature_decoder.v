// quadrature_decoder: conditioned A/B levels -> count pulses, direction and illegal transitions.
//
// Phase index g = {B, A ^ B} runs 0,1,2,3 for the levels AB = 00,10,11,01 when A leads B, which
// we call forward (count up). A step of +1 (mod 4) counts up, -1 counts down, +2 means A and B
// changed in the same sample: an illegal transition, reported on err_o and never counted.
// Decoding (mode_i, CONTROL.DECODE): X4 counts every legal transition; X2 only those where A
// changes (00<->10, 11<->01); X1 only 00<->10, so one count per cycle of the encoder and a
// reversal over the same edge cancels exactly.
// dir_o is the direction of the last legal transition seen while enabled (1 = down), in every mode.
// up_o/down_o/err_o are one-cycle pulses one clock after the sample that shows the change.
//
// Assumptions: a_i/b_i come from input_conditioner (synchronous); valid_i rises once after reset
// and stays high; mode_i is never the reserved value 3 (the register file refuses it; 3 decodes
// as X4 anyway). rst_i synchronous, active high.
// Guarantees (proven): a count pulse only on a legal transition and only while enabled, at most
// one of up/down per cycle (so a counter moves by exactly one); err_o exactly on a double change.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module quadrature_decoder (
    input  wire       clk_i,
    input  wire       rst_i,
    input  wire       a_i,
    input  wire       b_i,
    input  wire       valid_i,
    input  wire       en_i,
    input  wire [`OMNILOC_CONTROL_DECODE_W-1:0] mode_i,
    output wire       up_o,
    output wire       down_o,
    output wire       dir_o,
    output wire       err_o
);

reg [1:0] prev_g_q;
reg       primed_q;
reg       up_q;
reg       down_q;
reg       dir_q;
reg       err_q;

assign up_o = up_q;
assign down_o = down_q;
assign dir_o = dir_q;
assign err_o = err_q;

wire [1:0] g = {b_i, a_i ^ b_i};
wire [1:0] step = g - prev_g_q;
wire forward = (step == 2'd1);
wire backward = (step == 2'd3);
wire illegal = (step == 2'd2);

// The transition between g and prev_g_q, named by its lower phase when it is a legal step.
wire [1:0] low_g = forward ? prev_g_q : g;
wire selected = (mode_i == `OMNILOC_CONTROL_DECODE_X1) ? (low_g == 2'd0)
              : (mode_i == `OMNILOC_CONTROL_DECODE_X2) ? (low_g[0] == 1'b0)
              : 1'b1;
wire active = primed_q && en_i;

always @(posedge clk_i) begin
    if (rst_i) begin
        prev_g_q <= 2'd0;
        primed_q <= 1'b0;
        up_q <= 1'b0;
        down_q <= 1'b0;
        dir_q <= 1'b0;
        err_q <= 1'b0;
    end else begin
        // The phase is tracked even while disabled, so enabling never invents an edge.
        prev_g_q <= g;
        primed_q <= primed_q | valid_i;
        up_q <= active && forward && selected;
        down_q <= active && backward && selected;
        err_q <= active && illegal;
        if (active && (forward || backward)) dir_q <= backward;
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);

// Independent reference: the previous A/B levels, not the phase index.
reg f_a_q = 1'b0;
reg f_b_q = 1'b0;
always @(posedge clk_i) begin
    f_a_q <= rst_i ? 1'b0 : a_i;
    f_b_q <= rst_i ? 1'b0 : b_i;
end

// The register file never lets the reserved mode 3 through.
always @(*) assume (mode_i != 2'd3);

always @(*) begin
    if (f_past_valid && !rst_i) begin
        assert (!(up_q && down_q));
        assert (!((up_q || down_q) && err_q));
        assert (prev_g_q == {f_b_q, f_a_q ^ f_b_q});
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // No count and no error without enable (or before the first valid sample was seen).
        if (!$past(en_i) || !$past(primed_q)) assert (!up_q && !down_q && !err_q);
        // A count only on a legal transition: exactly one of A, B changed.
        if (up_q || down_q) assert (($past(a_i) != $past(f_a_q)) != ($past(b_i) != $past(f_b_q)));
        // Forward is A leading B: A rises while B is low, B rises while A is high, ...
        if (up_q) assert ($past(a_i) != $past(f_a_q) ? $past(a_i) != $past(b_i) : $past(a_i) == $past(b_i));
        if (down_q) assert ($past(a_i) != $past(f_a_q) ? $past(a_i) == $past(b_i) : $past(a_i) != $past(b_i));
        // Illegal exactly when both changed in the same sample (while enabled and primed).
        assert (err_q == ($past(en_i) && $past(primed_q) && $past(a_i) != $past(f_a_q) && $past(b_i) != $past(f_b_q)));
        // In X4 every legal transition counts.
        if ($past(en_i) && $past(primed_q) && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X4)
            assert ((up_q || down_q) == (($past(a_i) != $past(f_a_q)) != ($past(b_i) != $past(f_b_q))));
        // X1 and X2 count only on A edges; X1 only while B is low.
        if ((up_q || down_q) && $past(mode_i) != `OMNILOC_CONTROL_DECODE_X4) assert ($past(a_i) != $past(f_a_q));
        if ((up_q || down_q) && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X1) assert (!$past(b_i));
        // The direction changes only on a counted-or-not legal transition while enabled.
        if (dir_q != $past(dir_q)) assert ($past(en_i) && $past(primed_q) && (($past(a_i) != $past(f_a_q)) != ($past(b_i) != $past(f_b_q))));
    end
end

// Iff-properties: exactly which samples count, in which direction, per mode, from the A/B levels
// alone (f_*: A or B changed, the change is legal, A leads B; previous-cycle values via $past).
wire f_a_ch = a_i != f_a_q;
wire f_b_ch = b_i != f_b_q;
wire f_legal = f_a_ch != f_b_ch;
// A leads B (forward): A changes to differ from B, or B changes to equal A.
wire f_fwd = f_a_ch ? (a_i != b_i) : (a_i == b_i);
wire f_en = en_i && primed_q;
// The edges each mode counts: X4 every legal one, X2 the A edges, X1 the A edges while B is low.
wire f_counted = f_legal && ((mode_i == `OMNILOC_CONTROL_DECODE_X1) ? (f_a_ch && !b_i)
                           : (mode_i == `OMNILOC_CONTROL_DECODE_X2) ? f_a_ch : 1'b1);
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        assert (up_q == $past(f_en && f_counted && f_fwd));
        assert (down_q == $past(f_en && f_counted && !f_fwd));
        // The direction is that of the last legal transition while enabled, in every mode.
        if ($past(f_en && f_legal)) assert (dir_q == !$past(f_fwd));
        else assert (dir_q == $past(dir_q));
    end
end

// Each property reachable: counts both ways in every mode, an error, a reversal of direction.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (up_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X1);
        cover (down_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X1);
        cover (up_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X2);
        cover (down_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X2);
        cover (up_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X4 && $past(b_i));
        cover (down_q && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X4 && !$past(a_i) && $past(b_i));
        cover (err_q);
        cover (dir_q && !$past(dir_q));
        cover (!dir_q && $past(dir_q));
        // A legal X1 transition on the other edge pair is not counted.
        cover ($past(f_en && f_legal && f_a_ch && b_i) && $past(mode_i) == `OMNILOC_CONTROL_DECODE_X1 && !up_q && !down_q);
    end
end
`endif

endmodule

`resetall
